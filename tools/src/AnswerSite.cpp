#include "tetrapage/tools/AnswerSite.h"

#include "tetrapage/runtime/geometry/TriangleDistance.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"
#include "tetrapage/tools/CsvFile.h"

namespace tetrapage {
namespace {

const char* kind_name(AnswerSite::Kind kind) {
  switch (kind) {
    case AnswerSite::Kind::surface:
      return "surface";
    case AnswerSite::Kind::near:
      return "near";
    case AnswerSite::Kind::solid:
      return "solid";
    case AnswerSite::Kind::object_inside:
      return "object_inside";
    case AnswerSite::Kind::obstacle_inside:
      return "obstacle_inside";
    case AnswerSite::Kind::none:
      break;
  }
  return "";
}

// A point of the intersection: the mean of its corners (a point, a segment's midpoint, a point
// inside the convex polygon of a coplanar overlap).
Vec3 representative_point(const geometry::ContactGeometry& meet) {
  Vec3 mean{0, 0, 0};
  for (std::uint8_t i = 0; i < meet.count; ++i)
    for (int a = 0; a < 3; ++a) mean[a] += meet.points[i][a];
  for (double& x : mean) x /= double(meet.count);
  return mean;
}

std::string optional_point_fields(const std::optional<Vec3>& p) {
  return p ? point_fields(*p) : std::string(",,");
}

// part,part_name,part_path,dynamic_part of the environment side.
std::string environment_fields(const AnswerSite& site, const CollisionIndex& index,
                               const FlyingObject& object) {
  if (site.environment_part == Contact::kDynamicPart) {
    const DynamicObstacles::Part* part =
        object.obstacles() ? object.obstacles()->find(site.dynamic_part) : nullptr;
    const std::string name = csv_field(part ? part->name : std::string());
    std::string fields(1, ',');
    fields.append(name).append(1, ',').append(name).append(1, ',');
    return fields.append(std::to_string(site.dynamic_part));
  }
  const IndexParts& parts = index.parts();
  return std::to_string(site.environment_part) + ',' +
         csv_field(parts.name(site.environment_part)) + ',' +
         csv_field(parts.path(site.environment_part)) + ',';
}

// object_part,object_part_name,object_part_path of the object triangle (empty without one).
std::string object_part_fields(const AnswerSite& site, const TriangleSoup& mesh) {
  if (!site.object_triangle || *site.object_triangle >= mesh.triangle_count()) return ",,";
  const std::uint32_t part =
      *site.object_triangle < mesh.part_of.size() ? mesh.part_of[*site.object_triangle] : 0;
  if (part >= mesh.part_count()) return std::to_string(part) + ",,";
  return std::to_string(part) + ',' + csv_field(mesh.part_names[part]) + ',' +
         csv_field(mesh.part_path(part));
}

// The site of a pair of triangles, its kind left to the caller; a solid when there is no
// object triangle (Contact::kNoObjectTriangle, the one convention of contacts and answers).
AnswerSite pair_site(std::uint32_t environment_part, std::uint32_t dynamic_part,
                     std::uint64_t environment_triangle, std::uint32_t object_triangle) {
  AnswerSite site;
  site.environment_part = environment_part;
  site.dynamic_part = dynamic_part;
  site.environment_triangle = environment_triangle;
  if (object_triangle == Contact::kNoObjectTriangle)
    site.kind = AnswerSite::Kind::solid;
  else
    site.object_triangle = object_triangle;
  return site;
}

}  // namespace

AnswerSite contact_site(FlyingObject& object, const Contact& contact) {
  AnswerSite site = pair_site(contact.environment_part, contact.dynamic_part,
                              contact.environment_triangle, contact.object_triangle);
  if (site.kind == AnswerSite::Kind::solid) return site;
  const auto [environment, placed] = object.contact_triangles(contact);
  if (geometry::triangles_intersect(environment, placed)) {
    site.kind = AnswerSite::Kind::surface;
    const geometry::ContactGeometry meet = object.contact_geometry(contact);
    // The constructed intersection can come out empty where the exact test says the pair
    // meets at a single point: the closest points then stand for it.
    if (meet.count > 0) {
      site.on_environment = site.on_object = representative_point(meet);
      return site;
    }
  } else {
    site.kind = AnswerSite::Kind::near;
  }
  const geometry::TriangleDistance closest = geometry::triangle_distance(environment, placed);
  site.on_environment = closest.on_first;
  site.on_object = closest.on_second;
  return site;
}

AnswerSite containment_site(Containment containment, std::uint32_t part,
                            std::uint32_t dynamic_part) {
  AnswerSite site;
  if (containment == Containment::none) return site;
  site.kind = containment == Containment::object_inside_obstacle
                  ? AnswerSite::Kind::object_inside
                  : AnswerSite::Kind::obstacle_inside;
  site.environment_part = part;
  site.dynamic_part = dynamic_part;
  return site;
}

AnswerSite distance_site(const DistanceResult& result) {
  if (result.separation == Separation::farther) return {};
  const ContactSite& closest = result.closest;
  if (!closest.has_triangle())
    return containment_site(result.containment, result.containing_part,
                            result.containing_dynamic_part);
  AnswerSite site = pair_site(closest.environment_part, closest.dynamic_part,
                              closest.environment_triangle, closest.object_triangle);
  if (site.kind == AnswerSite::Kind::solid) return site;
  site.kind = result.separation == Separation::touching ? AnswerSite::Kind::surface
                                                        : AnswerSite::Kind::near;
  if (has_closest_points(result)) {
    site.on_environment = result.on_environment;
    site.on_object = result.on_object;
  }
  return site;
}

AnswerSite impact_site(FlyingObject& object, const ImpactResult& result) {
  if (result.impact != Impact::hit) return {};
  if (!result.contact.has_triangle())
    return containment_site(result.containment, result.containing_part,
                            result.containing_dynamic_part);
  return contact_site(object, result.contact);
}

std::string site_fields(const AnswerSite& site, const CollisionIndex& index,
                        const FlyingObject& object) {
  std::string fields = kind_name(site.kind);
  fields += ',';
  if (site.kind == AnswerSite::Kind::none) return fields.append(14, ',');
  fields += environment_fields(site, index, object);
  fields += ',';
  fields += site.environment_triangle ? std::to_string(*site.environment_triangle) : std::string();
  fields += ',';
  fields += object_part_fields(site, object.object());
  fields += ',';
  fields += site.object_triangle ? std::to_string(*site.object_triangle) : std::string();
  fields += ',';
  fields += optional_point_fields(site.on_environment);
  fields += ',';
  fields += optional_point_fields(site.on_object);
  return fields;
}

}  // namespace tetrapage
