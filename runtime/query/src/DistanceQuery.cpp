// FlyingObject::distance: the collision step decides touching; the distance search measures
// the rest (DistanceSearch.h).

#include <cmath>
#include <string>

#include "FlyingObjectParts.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/TriangleContact.h"
#include "tetrapage/runtime/query/FlyingObject.h"

namespace tetrapage {

namespace {

// A touching step's answer: distance 0, and the first contact's pair.
void report_touching(const QueryResult& touch, DistanceResult& result) {
  result.separation = Separation::touching;
  result.distance = result.lower_bound = result.upper_bound = 0;
  result.containment = touch.containment;
  result.containing_part = touch.containing_part;
  result.containing_dynamic_part = touch.containing_dynamic_part;
  if (touch.contacts.empty()) return;
  result.closest = touch.contacts.front();
  result.closest.environment_component = ContactSite::kNoComponent;  // a distance names none
}

}  // namespace

std::pair<geometry::Triangle, geometry::Triangle> FlyingObject::contact_triangles(
    const Contact& contact) {
  if (contact.object_triangle == Contact::kNoObjectTriangle)
    throw InputError(
        "contact triangles: a contact of a solid has no object triangle (environment triangle " +
        std::to_string(contact.environment_triangle) + ")");
  if (contact.dynamic_part != kNoDynamicPart) return dynamic_contact_triangles(contact);
  if (contact.object_triangle >= model_->mesh.triangles.size())
    throw InputError("contact geometry: the object has no triangle " +
                     std::to_string(contact.object_triangle));
  const geometry::Triangle placed = parts_->object.world_triangle(contact.object_triangle);
  // The triangle phase II tested (a float copy is its shard's own); a contact the last step
  // did not report is looked up in the index.
  // Callers walk the contacts in order: the search starts where the last one was found.
  const ContactTriangles& tested = parts_->contact_triangles;
  for (std::size_t k = 0; k < tested.size(); ++k) {
    const std::size_t at = (parts_->contact_cursor + k) % tested.size();
    if (tested[at].first != contact.environment_triangle) continue;
    parts_->contact_cursor = at;
    return {tested[at].second, placed};
  }
  const auto stored = index_->stored_triangle(contact.environment_triangle);
  if (!stored)
    throw InputError("contact geometry: the index holds no triangle " +
                     std::to_string(contact.environment_triangle));
  return {stored->corners, placed};
}

geometry::ContactGeometry FlyingObject::contact_geometry(const Contact& contact) {
  if (contact.object_triangle == Contact::kNoObjectTriangle) return {};
  const auto [environment, object] = contact_triangles(contact);
  return geometry::contact_geometry(environment, object);
}

void FlyingObject::distance(const Pose& pose, const DistanceOptions& options,
                            DistanceResult& result) {
  if (!(options.max_distance >= 0))
    throw InputError("distance query: max_distance must be >= 0, not " +
                     std::to_string(options.max_distance));
  Parts& parts = *parts_;
  result = DistanceResult{};
  // Touching is the collision query's exact answer (contacts and containment).
  query(pose, QueryOptions{}, parts.touch);
  if (parts.touch.collides) {
    report_touching(parts.touch, result);
    // The closest points: a point both triangles share.
    if (!parts.touch.contacts.empty()) {
      const geometry::ContactGeometry shared = contact_geometry(parts.touch.contacts.front());
      if (shared.count > 0) result.on_environment = result.on_object = shared.points[0];
    }
    return;
  }
  const geometry::Box& box = parts.coherence.current_box();
  // In free space, the free box's depth bounds the distance: planners' "farther" is free.
  if (const double gap = parts.coherence.free_gap(box); gap > options.max_distance) {
    result.separation = Separation::farther;
    result.distance = result.lower_bound = gap;
    result.from_free_box = true;
    return;
  }
  parts.distance.measure(*model_, parts.object, box, options.max_distance, parts.obstacles.get(),
                         result);
}

}  // namespace tetrapage
