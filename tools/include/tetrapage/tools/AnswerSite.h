#pragma once
/// @file AnswerSite.h
/// The columns every answer file of `fly` (--contacts, and --answers of --query contacts,
/// distance and toi) shares to say where the object meets the environment, or comes closest
/// to it, in one vocabulary (docs/USAGE.md, "Answer files"):
///   kind,part,part_name,part_path,dynamic_part,environment_triangle,
///   object_part,object_part_name,object_part_path,object_triangle,
///   environment_x,environment_y,environment_z,object_x,object_y,object_z
/// kind is
///   surface          the two triangles meet (exactly); both points are one point of their
///                    intersection (the mean of contact_geometry's corners);
///   near             they do not meet: a pair within a clearance accuracy's distance, or
///                    the closest pair of a distance answer; the points are the closest points
///                    on each;
///   solid            an environment triangle meets the object checked as a solid (hull, box
///                    or swept accuracy): no object triangle, no points;
///   object_inside    the object lies inside the environment part named (containment);
///   obstacle_inside  the environment part named lies inside the object; no triangles, no
///                    points (the object's part columns are empty);
///   (empty)          no site: a distance farther than --max-distance, a motion with no hit.
/// part, part_name and part_path name the environment part (as the index names it); for a
/// dynamic obstacle part is empty, part_name and part_path are the obstacle's name and
/// dynamic_part its id (environment_triangle is then the triangle's index in the obstacle's
/// mesh). object_part and its name and path name the part of the flying object (a manifest
/// or a STEP assembly flies as several parts) that holds object_triangle.

#include <cstdint>
#include <optional>
#include <string>

#include "tetrapage/runtime/query/FlyingObject.h"

namespace tetrapage {

struct AnswerSite {
  enum class Kind : std::uint8_t { none, surface, near, solid, object_inside, obstacle_inside };
  Kind kind = Kind::none;
  std::uint32_t environment_part = 0;  ///< Contact::kDynamicPart for a dynamic obstacle
  std::uint32_t dynamic_part = 0;
  std::optional<std::uint64_t> environment_triangle;
  std::optional<std::uint32_t> object_triangle;
  std::optional<Vec3> on_environment, on_object;
};

/// The header of the site columns (no leading or trailing comma).
inline constexpr const char* kAnswerSiteHeader =
    "kind,part,part_name,part_path,dynamic_part,environment_triangle,object_part,"
    "object_part_name,object_part_path,object_triangle,environment_x,environment_y,"
    "environment_z,object_x,object_y,object_z";

/// The site of a contact of `object`'s last query: surface or near by the exact test of its
/// two triangles, with their points; solid when it has no object triangle.
/// @throw as FlyingObject::contact_triangles.
AnswerSite contact_site(FlyingObject& object, const Contact& contact);
/// The site of a containment (Containment::none gives an empty site).
AnswerSite containment_site(Containment containment, std::uint32_t part,
                            std::uint32_t dynamic_part);
/// The site of a distance answer: its closest pair (surface when touching, near when apart),
/// its containment, or none when farther.
AnswerSite distance_site(const DistanceResult& result);
/// The site of a time-of-impact answer: the contact or containment at contact_at, or none.
/// `object` is at contact_at's pose (time_of_impact leaves it there).
AnswerSite impact_site(FlyingObject& object, const ImpactResult& result);

/// The site columns of a row, names looked up in the index, the object and its obstacles.
std::string site_fields(const AnswerSite& site, const CollisionIndex& index,
                        const FlyingObject& object);

}  // namespace tetrapage
