#include "tetrapage/tools/QueryAnswerFile.h"

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/tools/AnswerSite.h"

namespace tetrapage {

namespace {

std::string header_of(FlyQuery query) {
  const std::string site = std::string("step,") + kAnswerSiteHeader;
  switch (query) {
    case FlyQuery::contacts:
      return site +
             ",shape,x1,y1,z1,x2,y2,z2,polygon,environment_nx,environment_ny,environment_nz,"
             "object_nx,object_ny,object_nz";
    case FlyQuery::distance:
      return site + ",separation,distance,lower_bound,upper_bound";
    case FlyQuery::time_of_impact:
      return site + ",impact,free_until,contact_at,iterations";
    case FlyQuery::collide:
      break;
  }
  throw InputError("fly: --query collide writes its answers as step,collides");
}

const char* shape_name(geometry::ContactShape shape) {
  switch (shape) {
    case geometry::ContactShape::point:
      return "point";
    case geometry::ContactShape::segment:
      return "segment";
    case geometry::ContactShape::polygon:
      return "polygon";
    case geometry::ContactShape::none:
      break;
  }
  return "none";
}

// The geometry columns of a contact row: shape, two points, the polygon, both normals.
std::string geometry_fields(const geometry::ContactGeometry& meet) {
  std::string fields(shape_name(meet.shape));
  fields += ',';
  fields += meet.count > 0 ? point_fields(meet.points[0]) : std::string(",,");
  fields += ',';
  fields += meet.count > 1    ? point_fields(meet.points[1])
            : meet.count == 1 ? point_fields(meet.points[0])
                              : ",,";
  fields += ',';
  if (meet.shape == geometry::ContactShape::polygon)
    for (std::uint8_t i = 0; i < meet.count; ++i) {
      const geometry::Point& p = meet.points[i];
      if (i > 0) fields += ';';
      fields.append(number_field(p[0]))
          .append(" ")
          .append(number_field(p[1]))
          .append(" ")
          .append(number_field(p[2]));
    }
  return fields + ',' + point_fields(meet.first_normal) + ',' + point_fields(meet.second_normal);
}

}  // namespace

FlyQuery parse_fly_query(const std::string& text) {
  if (text == "collide") return FlyQuery::collide;
  if (text == "contacts") return FlyQuery::contacts;
  if (text == "distance") return FlyQuery::distance;
  if (text == "toi") return FlyQuery::time_of_impact;
  throw InputError("--query must be collide, contacts, distance or toi, not '" + text + "'");
}

const char* fly_query_name(FlyQuery query) {
  switch (query) {
    case FlyQuery::collide:
      return "collide";
    case FlyQuery::contacts:
      return "contacts";
    case FlyQuery::distance:
      return "distance";
    case FlyQuery::time_of_impact:
      return "toi";
  }
  return "collide";
}

QueryAnswerFile::QueryAnswerFile(const std::filesystem::path& path, FlyQuery query,
                                 const CollisionIndex& index)
    : file_(path, header_of(query)), index_(index) {}

void QueryAnswerFile::write_contacts(std::uint64_t step, FlyingObject& object,
                                     const QueryResult& result) {
  const std::string prefix = std::to_string(step) + ',';
  if (result.containment != Containment::none)
    file_.row(prefix +
              site_fields(containment_site(result.containment, result.containing_part,
                                           result.containing_dynamic_part),
                          index_, object) +
              ",none,,,,,,,,,,,,,");
  for (const Contact& contact : result.contacts) {
    const AnswerSite site = contact_site(object, contact);
    std::string row = prefix + site_fields(site, index_, object) + ',';
    row += contact.object_triangle == Contact::kNoObjectTriangle
               ? std::string("none,,,,,,,,,,,,,")
               : geometry_fields(object.contact_geometry(contact));
    file_.row(row);
  }
}

void QueryAnswerFile::write_distance(std::uint64_t step, FlyingObject& object,
                                     const DistanceResult& result) {
  file_.row(std::to_string(step) + ',' + site_fields(distance_site(result), index_, object) + ',' +
            to_string(result.separation) + ',' + number_field(result.distance) + ',' +
            number_field(result.lower_bound) + ',' + number_field(result.upper_bound));
}

void QueryAnswerFile::write_impact(std::uint64_t step, FlyingObject& object,
                                   const ImpactResult& result) {
  file_.row(std::to_string(step) + ',' + site_fields(impact_site(object, result), index_, object) +
            ',' + to_string(result.impact) + ',' + number_field(result.free_until) + ',' +
            number_field(result.contact_at) + ',' + std::to_string(result.iterations));
}

}  // namespace tetrapage
