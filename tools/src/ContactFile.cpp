#include "tetrapage/tools/ContactFile.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <cstdio>

#include "tetrapage/formats/Error.h"

namespace tetrapage {
namespace {

using Epeck = CGAL::Exact_predicates_exact_constructions_kernel;

Epeck::Triangle_3 to_epeck(const std::array<Vec3, 3>& t) {
  return {{t[0][0], t[0][1], t[0][2]}, {t[1][0], t[1][1], t[1][2]}, {t[2][0], t[2][1], t[2][2]}};
}

Vec3 to_double(const Epeck::Point_3& p) {
  return {CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())};
}

// A representative point of whatever the intersection is: a point, a segment's midpoint, the
// centroid of a triangle or of a polygon's corners.
struct RepresentativePoint {
  using result_type = Vec3;
  Vec3 operator()(const Epeck::Point_3& p) const { return to_double(p); }
  Vec3 operator()(const Epeck::Segment_3& s) const {
    return to_double(CGAL::midpoint(s.source(), s.target()));
  }
  Vec3 operator()(const Epeck::Triangle_3& t) const { return to_double(CGAL::centroid(t)); }
  Vec3 operator()(const std::vector<Epeck::Point_3>& points) const {
    Epeck::FT x = 0, y = 0, z = 0;
    for (const auto& p : points) x += p.x(), y += p.y(), z += p.z();
    const Epeck::FT n = int(points.size());
    return to_double(Epeck::Point_3(x / n, y / n, z / n));
  }
};

}  // namespace

std::optional<Vec3> triangle_intersection_point(const std::array<Vec3, 3>& a,
                                                const std::array<Vec3, 3>& b) {
  const Epeck::Triangle_3 ta = to_epeck(a), tb = to_epeck(b);
  if (ta.is_degenerate() || tb.is_degenerate()) return std::nullopt;
  const auto result = CGAL::intersection(ta, tb);
  if (!result) return std::nullopt;
  return boost::apply_visitor(RepresentativePoint{}, *result);
}

ContactFile::ContactFile(const std::filesystem::path& path, const CollisionIndex& index,
                         const TriangleSoup& object)
    : file_(path, "step,kind,part,part_name,part_path,environment_triangle,object_triangle,x,y,z",
            "contacts file"),
      index_(index),
      object_(object) {}

void ContactFile::write_row(std::uint64_t step, const char* kind, std::uint32_t part,
                            const std::string& rest) {
  const IndexParts& parts = index_.parts();
  file_.row(std::to_string(step) + ',' + kind + ',' + std::to_string(part) + ',' +
            csv_field(parts.name(part)) + ',' + csv_field(parts.path(part)) + ',' + rest);
}

void ContactFile::write_step(std::uint64_t step, const Pose& pose, const QueryResult& result) {
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
    if (contact.environment_triangle != last_id_) {
      last_triangle_ = index_.stored_triangle(contact.environment_triangle);
      last_id_ = contact.environment_triangle;
    }
    const auto& stored = last_triangle_;
    if (stored) {
      std::array<Vec3, 3> placed = object_.corners(contact.object_triangle);
      for (Vec3& p : placed) p = apply_pose(pose, p);
      if (const auto meet = triangle_intersection_point(stored->corners, placed))
        point = number_field((*meet)[0]) + "," + number_field((*meet)[1]) + "," +
                number_field((*meet)[2]);
    }
    write_row(step, "surface", contact.environment_part,
              environment + "," + std::to_string(contact.object_triangle) + "," + point);
  }
}

}  // namespace tetrapage
