// The C API's dynamic obstacles (tetrapage.h, "Dynamic obstacles") over DynamicObstacles, with
// the handles and the guarded calls of CApiSupport.h.

#include <algorithm>
#include <memory>
#include <string>
#include <utility>

#include "CApiSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/tetrapage.h"

using namespace tetrapage::capi;

namespace {

// Objects hold the overlay as shared_ptr<const>: a change through the handle is seen by their
// next step (the C++ threading rule: changes between steps).
struct ObstaclesState {
  std::shared_ptr<tetrapage::DynamicObstacles> obstacles;
};

// Never destroyed, as the other tables (CApiSupport.h).
HandleTable<ObstaclesState>& overlays() {
  static auto* table = new HandleTable<ObstaclesState>("obstacles");
  return *table;
}

std::shared_ptr<ObstaclesState> obstacles_state(const tetrapage_obstacles* obstacles) {
  require(obstacles, "obstacles");
  return overlays().get(id_of(obstacles));
}

tetrapage::Pose pose_from(const double pose[7]) {
  require(pose, "pose");
  tetrapage::Pose placed;
  placed.translation = {pose[0], pose[1], pose[2]};
  placed.rotation = {pose[3], pose[4], pose[5], pose[6]};
  return placed;
}

tetrapage_obstacles* add_overlay(tetrapage::DynamicObstacles overlay) {
  auto state = std::make_shared<ObstaclesState>(
      ObstaclesState{std::make_shared<tetrapage::DynamicObstacles>(std::move(overlay))});
  return reinterpret_cast<tetrapage_obstacles*>(overlays().add(std::move(state)));
}

}  // namespace

std::shared_ptr<const tetrapage::DynamicObstacles> tetrapage::capi::obstacles_of(
    const tetrapage_obstacles* obstacles) {
  return obstacles ? obstacles_state(obstacles)->obstacles : nullptr;
}

extern "C" {

tetrapage_status tetrapage_obstacles_create(tetrapage_index* index,
                                            tetrapage_obstacles** obstacles) {
  if (obstacles) *obstacles = nullptr;
  return guarded(__func__, [&] {
    const auto state = index_state(index);
    require(obstacles, "obstacles");
    *obstacles = add_overlay(tetrapage::DynamicObstacles(state->index));
  });
}

tetrapage_status tetrapage_obstacles_destroy(tetrapage_obstacles* obstacles) {
  return guarded(__func__, [&] {
    if (obstacles == nullptr) return;
    overlays().remove(id_of(obstacles)).reset();
  });
}

tetrapage_status tetrapage_obstacles_insert(tetrapage_obstacles* obstacles, const double* vertices,
                                            size_t vertex_count, const uint32_t* triangles,
                                            size_t triangle_count, const double pose[7],
                                            const char* name, uint32_t* id) {
  if (id) *id = 0;
  return guarded(__func__, [&] {
    const auto state = obstacles_state(obstacles);
    require(id, "id");
    if (vertex_count > 0) require(vertices, "vertices");
    if (triangle_count > 0) require(triangles, "triangles");
    auto soup = object_soup(vertices, vertex_count, triangles, triangle_count);
    if (name != nullptr) soup.part_names = {name};
    *id = state->obstacles->insert(std::move(soup), pose_from(pose), name ? name : "");
  });
}

tetrapage_status tetrapage_obstacles_move(tetrapage_obstacles* obstacles, uint32_t id,
                                          const double pose[7]) {
  return guarded(__func__,
                 [&] { obstacles_state(obstacles)->obstacles->move(id, pose_from(pose)); });
}

tetrapage_status tetrapage_obstacles_remove(tetrapage_obstacles* obstacles, uint32_t id) {
  return guarded(__func__, [&] { obstacles_state(obstacles)->obstacles->remove(id); });
}

tetrapage_status tetrapage_obstacles_hide_part(tetrapage_obstacles* obstacles, uint32_t part,
                                               int hidden) {
  return guarded(__func__, [&] {
    const auto state = obstacles_state(obstacles);
    if (hidden)
      state->obstacles->hide_part(part);
    else
      state->obstacles->show_part(part);
  });
}

tetrapage_status tetrapage_object_set_obstacles(tetrapage_object* object,
                                                tetrapage_obstacles* obstacles) {
  return guarded(__func__, [&] {
    const auto state = object_state(object);
    state->has_result = false;  // the last answer was without (or with other) obstacles
    state->flying.set_obstacles(obstacles_of(obstacles));
  });
}

tetrapage_status tetrapage_obstacles_save(const tetrapage_obstacles* obstacles, const char* path) {
  return guarded(__func__, [&] {
    const auto state = obstacles_state(obstacles);
    require(path, "path");
    state->obstacles->save(path);
  });
}

tetrapage_status tetrapage_obstacles_load(tetrapage_index* index, const char* path,
                                          tetrapage_obstacles** obstacles) {
  if (obstacles) *obstacles = nullptr;
  return guarded(__func__, [&] {
    const auto state = index_state(index);
    require(path, "path");
    require(obstacles, "obstacles");
    *obstacles = add_overlay(tetrapage::DynamicObstacles::load(state->index, path));
  });
}

}  // extern "C"
