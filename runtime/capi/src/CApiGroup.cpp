// The C API's groups of objects (tetrapage.h, "Groups of objects") over ObjectGroup, with the
// handles and the guarded calls of CApiSupport.h.

#include <algorithm>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "CApiSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/query/ObjectGroup.h"
#include "tetrapage/tetrapage.h"

using namespace tetrapage::capi;

namespace {

struct GroupState {
  tetrapage::ObjectGroup group;
  tetrapage::GroupResult result;
  bool has_result = false;
};

// Never destroyed, as the other tables (CApiSupport.h).
HandleTable<GroupState>& groups() {
  static auto* table = new HandleTable<GroupState>("group");
  return *table;
}

std::shared_ptr<GroupState> group_state(const tetrapage_group* group) {
  require(group, "group");
  return groups().get(id_of(group));
}

}  // namespace

extern "C" {

tetrapage_status tetrapage_group_create(tetrapage_index* index, tetrapage_object* const* objects,
                                        size_t count, tetrapage_group** group) {
  if (group) *group = nullptr;
  return guarded(__func__, [&] {
    const auto state = index_state(index);
    require(objects, "objects");
    require(group, "group");
    if (count == 0) throw tetrapage::InputError("a group needs at least one object, not 0");
    std::vector<std::shared_ptr<const tetrapage::ObjectModel>> models;
    models.reserve(count);
    for (size_t k = 0; k < count; ++k) {
      if (objects[k] == nullptr) {
        // NullArgument keeps the pointer: the name must outlive this call's frame.
        thread_local std::string name;
        name = "objects[" + std::to_string(k) + "]";
        throw NullArgument(name.c_str());
      }
      models.push_back(object_state(objects[k])->flying.model());
    }
    auto created = std::make_shared<GroupState>(
        GroupState{tetrapage::ObjectGroup(state->index, std::move(models)), {}, false});
    *group = reinterpret_cast<tetrapage_group*>(groups().add(std::move(created)));
  });
}

tetrapage_status tetrapage_group_destroy(tetrapage_group* group) {
  return guarded(__func__, [&] {
    if (group == nullptr) return;
    groups().remove(id_of(group)).reset();
  });
}

tetrapage_status tetrapage_group_set_obstacles(tetrapage_group* group,
                                               tetrapage_obstacles* obstacles) {
  return guarded(__func__, [&] {
    const auto state = group_state(group);
    state->has_result = false;
    state->group.set_obstacles(obstacles_of(obstacles));
  });
}

tetrapage_status tetrapage_group_step(tetrapage_group* group, const double* poses, int all_contacts,
                                      size_t* colliding_pairs) {
  if (colliding_pairs) *colliding_pairs = 0;
  return guarded(__func__, [&] {
    const auto state = group_state(group);
    state->has_result = false;  // a failed step leaves no answer behind
    require(poses, "poses");
    require(colliding_pairs, "colliding_pairs");
    std::vector<tetrapage::Pose> placed(state->group.size());
    for (std::size_t k = 0; k < placed.size(); ++k) {
      const double* pose = poses + 7 * k;
      placed[k].translation = {pose[0], pose[1], pose[2]};
      placed[k].rotation = {pose[3], pose[4], pose[5], pose[6]};
    }
    tetrapage::GroupQueryOptions options;
    const auto mode =
        all_contacts ? tetrapage::QueryMode::all_contacts : tetrapage::QueryMode::first_hit;
    options.environment.mode = mode;
    options.pair_mode = mode;
    state->group.step(placed, options, state->result);
    state->has_result = true;
    *colliding_pairs = state->result.pairs.size();
  });
}

tetrapage_status tetrapage_group_pairs(const tetrapage_group* group, uint32_t* pairs,
                                       size_t capacity, size_t* written) {
  if (written) *written = 0;
  return guarded(__func__, [&] {
    const auto state = group_state(group);
    require(written, "written");
    if (capacity > 0) require(pairs, "pairs");
    if (!state->has_result) return;
    const auto& found = state->result.pairs;
    const std::size_t n = std::min(capacity, found.size());
    for (std::size_t i = 0; i < n; ++i) {
      pairs[2 * i] = found[i].first;
      pairs[2 * i + 1] = found[i].second;
    }
    *written = n;
  });
}

tetrapage_status tetrapage_group_pair_triangles(const tetrapage_group* group, size_t pair,
                                                uint32_t* triangles, size_t capacity,
                                                size_t* written, int* containment) {
  if (written) *written = 0;
  if (containment) *containment = 0;
  return guarded(__func__, [&] {
    const auto state = group_state(group);
    require(written, "written");
    if (capacity > 0) require(triangles, "triangles");
    const std::size_t pairs = state->has_result ? state->result.pairs.size() : 0;
    if (pair >= pairs)
      throw tetrapage::InputError("no colliding pair " + std::to_string(pair) +
                                  " (the last step has " + std::to_string(pairs) + ")");
    const auto& found = state->result.pairs[pair];
    const auto contacts = state->result.triangles_of(found);
    const std::size_t n = std::min(capacity, contacts.size());
    for (std::size_t i = 0; i < n; ++i) {
      triangles[2 * i] = contacts[i].first_triangle;
      triangles[2 * i + 1] = contacts[i].second_triangle;
    }
    *written = n;
    if (containment) *containment = int(found.containment);
  });
}

tetrapage_status tetrapage_group_environment(const tetrapage_group* group, int* collides,
                                             size_t capacity, size_t* written) {
  if (written) *written = 0;
  return guarded(__func__, [&] {
    const auto state = group_state(group);
    require(written, "written");
    if (capacity > 0) require(collides, "collides");
    if (!state->has_result) return;
    const auto& found = state->result.environment;
    const std::size_t n = std::min(capacity, found.size());
    for (std::size_t i = 0; i < n; ++i) collides[i] = found[i].collides ? 1 : 0;
    *written = n;
  });
}

}  // extern "C"
