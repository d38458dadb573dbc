#include "tetrapage/tools/ContactFile.h"

#include <cstdio>

#include "tetrapage/formats/Error.h"

namespace tetrapage {
namespace {

// A point of the intersection: the mean of its corners (a point, a segment's midpoint, a point
// inside the convex polygon of a coplanar overlap).
Vec3 representative_point(const geometry::ContactGeometry& meet) {
  Vec3 mean{0, 0, 0};
  for (std::uint8_t i = 0; i < meet.count; ++i)
    for (int a = 0; a < 3; ++a) mean[a] += meet.points[i][a];
  for (double& x : mean) x /= double(meet.count);
  return mean;
}

}  // namespace

ContactFile::ContactFile(const std::filesystem::path& path, const CollisionIndex& index)
    : file_(path, "step,kind,part,part_name,part_path,environment_triangle,object_triangle,x,y,z"),
      index_(index) {}

void ContactFile::write_row(std::uint64_t step, const char* kind, std::uint32_t part,
                            const std::string& rest) {
  const IndexParts& parts = index_.parts();
  file_.row(std::to_string(step) + ',' + kind + ',' + std::to_string(part) + ',' +
            csv_field(parts.name(part)) + ',' + csv_field(parts.path(part)) + ',' + rest);
}

void ContactFile::write_step(std::uint64_t step, FlyingObject& object, const QueryResult& result) {
  if (result.containment != Containment::none) {
    write_row(step,
              result.containment == Containment::object_inside_obstacle ? "object_inside"
                                                                        : "obstacle_inside",
              result.containing_part, ",,,,");
  }
  for (const Contact& contact : result.contacts) {
    const std::string environment = std::to_string(contact.environment_triangle);
    if (contact.object_triangle == Contact::kNoObjectTriangle) {
      write_row(step, "solid", contact.environment_part, environment + ",,,,");
      continue;
    }
    std::string point = ",,";
    if (const geometry::ContactGeometry meet = object.contact_geometry(contact); meet.count > 0) {
      const Vec3 p = representative_point(meet);
      point = number_field(p[0]) + "," + number_field(p[1]) + "," + number_field(p[2]);
    }
    write_row(step, "surface", contact.environment_part,
              environment + "," + std::to_string(contact.object_triangle) + "," + point);
  }
}

}  // namespace tetrapage
