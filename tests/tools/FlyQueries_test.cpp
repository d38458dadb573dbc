// `tetrapage fly --query contacts|distance|toi` and fly with several objects, end to end,
// against CGAL: every contact row's points lie on both triangles, which do meet; every distance
// row's value is CGAL's exact distance over all pairs, within its bracket; every toi hit's
// contact pose collides and the motion is free before it at sampled times; a group's rows are
// the brute-force object/environment and object/object answers.
#include <gtest/gtest.h>
#include <unistd.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "BoxSoup.h"
#include "RunCli.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/runtime/query/PoseMotion.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
using Inexact = CGAL::Exact_predicates_inexact_constructions_kernel;

// The site columns every answer file of fly shares (AnswerSite.h), after "step".
const std::string kSite =
    "step,kind,part,part_name,part_path,dynamic_part,environment_triangle,object_part,object_part_"
    "name,"
    "object_part_path,object_triangle,environment_x,environment_y,environment_z,object_x,object_y,"
    "object_z";

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields(1);
  for (const char c : line) {
    if (c == ',')
      fields.emplace_back();
    else
      fields.back() += c;
  }
  return fields;
}

std::vector<std::vector<std::string>> read_rows(const fs::path& path, const std::string& header) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, header) << path;
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) rows.push_back(split_fields(line));
  return rows;
}

// An answer file's rows by column name (names without commas in this test's files).
struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::size_t column(const std::string& name) const {
    const auto at = std::find(header.begin(), header.end(), name);
    EXPECT_NE(at, header.end()) << name;
    return std::size_t(at - header.begin());
  }
  const std::string& at(std::size_t row, const std::string& name) const {
    return rows[row][column(name)];
  }
};

Table read_table(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  Table table{split_fields(line), {}};
  while (std::getline(in, line)) {
    table.rows.push_back(split_fields(line));
    EXPECT_EQ(table.rows.back().size(), table.header.size()) << path << ": " << line;
  }
  return table;
}

Vec3 point_of(const Table& table, std::size_t row, const std::string& prefix) {
  return {std::stod(table.at(row, prefix + "_x")), std::stod(table.at(row, prefix + "_y")),
          std::stod(table.at(row, prefix + "_z"))};
}

template <class K>
typename K::Triangle_3 triangle(const std::array<Vec3, 3>& t) {
  return {{t[0][0], t[0][1], t[0][2]}, {t[1][0], t[1][1], t[1][2]}, {t[2][0], t[2][1], t[2][2]}};
}

std::array<Vec3, 3> placed(const TriangleSoup& soup, std::size_t t, const Pose& pose) {
  std::array<Vec3, 3> corners = soup.corners(t);
  for (Vec3& c : corners) c = apply_pose(pose, c);
  return corners;
}

bool touches(const TriangleSoup& a, const Pose* pose_a, const TriangleSoup& b, const Pose& pose_b) {
  for (std::size_t i = 0; i < a.triangle_count(); ++i) {
    const auto ta = triangle<Inexact>(pose_a ? placed(a, i, *pose_a) : a.corners(i));
    for (std::size_t j = 0; j < b.triangle_count(); ++j)
      if (CGAL::do_intersect(ta, triangle<Inexact>(placed(b, j, pose_b)))) return true;
  }
  return false;
}

class FlyQueries : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::path(TETRAPAGE_TEST_TMP) / ("fly-queries-" + std::to_string(::getpid()));
    fs::remove_all(folder_);
    fs::create_directories(folder_);
    test::add_box(environment_, {0.0, 0.0, 0.0}, {1.0, 1.0, 0.05});
    test::add_box(environment_, {0.2, 0.2, 0.05}, {0.3, 0.3, 0.4});
    test::add_box(environment_, {0.6, 0.5, 0.05}, {0.75, 0.7, 0.3});
    write_mesh(folder_ / "scene.ply", environment_);
    test::add_box(object_, {-0.04, -0.03, -0.02}, {0.04, 0.03, 0.02});
    write_mesh(folder_ / "object.ply", object_);
    std::string out;
    ASSERT_EQ(test::run_cli("preprocess " + path("scene.ply") + " -o " + path("scene.tpi"), out), 0)
        << out;
    for (const char* seed : {"3", "4"})
      ASSERT_EQ(test::run_cli("generate flight --env " + path("scene.ply") + " --object " +
                                  path("object.ply") + " --steps 150 --displacement 0.02 --seed " +
                                  seed + " -o " + path(std::string("flight") + seed + ".csv"),
                              out),
                0)
          << out;
    poses_ = read_poses(folder_ / "flight3.csv");
  }
  void TearDown() override { fs::remove_all(folder_); }
  std::string path(const std::string& name) const { return (folder_ / name).string(); }
  std::string fly(const std::string& options) const {
    std::string out;
    EXPECT_EQ(test::run_cli("fly " + path("scene.tpi") + " --object " + path("object.ply") +
                                " --path " + path("flight3.csv") + " " + options,
                            out),
              0)
        << out;
    return out;
  }

  fs::path folder_;
  TriangleSoup environment_, object_;
  std::vector<Pose> poses_;
};

TEST_F(FlyQueries, DistanceRowsAreTheExactDistance) {
  fly("--query distance --answers " + path("d.csv"));
  const auto rows =
      read_rows(folder_ / "d.csv", kSite + ",separation,distance,lower_bound,upper_bound");
  ASSERT_EQ(rows.size(), poses_.size());
  int apart = 0, touching = 0;
  for (const auto& row : rows) {
    ASSERT_EQ(row.size(), 21u);
    const Pose& pose = poses_[std::stoul(row[0])];
    Exact::FT least = -1;
    for (std::size_t e = 0; e < environment_.triangle_count(); ++e)
      for (std::size_t o = 0; o < object_.triangle_count(); ++o) {
        const Exact::FT d = CGAL::squared_distance(triangle<Exact>(environment_.corners(e)),
                                                   triangle<Exact>(placed(object_, o, pose)));
        if (least < 0 || d < least) least = d;
      }
    if (row[17] == "touching") {
      ++touching;
      EXPECT_EQ(least, 0) << "step " << row[0];
      continue;
    }
    ASSERT_EQ(row[17], "apart");
    EXPECT_EQ(row[1], "near");  // the closest pair, its points on the environment and the object
    ++apart;
    const Exact::FT lower(std::stod(row[19])), upper(std::stod(row[20]));
    EXPECT_LE(lower * lower, least) << "step " << row[0];
    EXPECT_GE(upper * upper, least) << "step " << row[0];
  }
  EXPECT_GT(apart, 20);
  EXPECT_GT(touching, 0);
}

TEST_F(FlyQueries, ContactRowsLieOnTrianglesThatMeet) {
  fly("--query contacts --answers " + path("c.csv"));
  const auto rows = read_rows(folder_ / "c.csv",
                              kSite +
                                  ",shape,x1,y1,z1,x2,y2,z2,polygon,environment_nx,environment_ny,"
                                  "environment_nz,object_nx,object_ny,object_nz");
  ASSERT_GT(rows.size(), 5u);
  for (const auto& row : rows) {
    ASSERT_EQ(row.size(), 31u);
    ASSERT_EQ(row[1], "surface");
    const auto e = triangle<Exact>(environment_.corners(std::stoull(row[6])));
    const auto o =
        triangle<Exact>(placed(object_, std::stoul(row[10]), poses_[std::stoul(row[0])]));
    EXPECT_TRUE(CGAL::do_intersect(e, o));
    EXPECT_NE(row[17], "none");
    for (const int first : {11, 14, 18, 21}) {
      const Exact::Point_3 p(std::stod(row[first]), std::stod(row[first + 1]),
                             std::stod(row[first + 2]));
      EXPECT_LT(CGAL::to_double(CGAL::squared_distance(p, e)), 1e-24);
      EXPECT_LT(CGAL::to_double(CGAL::squared_distance(p, o)), 1e-24);
    }
  }
}

TEST_F(FlyQueries, ImpactRowsBracketTheFirstContact) {
  fly("--query toi --toi-tolerance 1e-3 --answers " + path("t.csv"));
  const auto rows =
      read_rows(folder_ / "t.csv", kSite + ",impact,free_until,contact_at,iterations");
  ASSERT_EQ(rows.size(), poses_.size());
  int hits = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto& row = rows[i];
    ASSERT_EQ(row.size(), 21u);
    ASSERT_NE(row[17], "unresolved");
    const PoseMotion motion(poses_[i - 1], poses_[i]);
    const double free_until = std::stod(row[18]), contact_at = std::stod(row[19]);
    for (int s = 0; s < 20 && free_until > 0; ++s)
      EXPECT_FALSE(touches(environment_, nullptr, object_, motion.at(free_until * s / 20.0)))
          << "step " << i;
    if (row[17] == "hit") {
      ++hits;
      EXPECT_EQ(row[1], "surface");  // the first contact at contact_at, on both triangles
      EXPECT_LE(contact_at - free_until, 1e-3);
      EXPECT_TRUE(touches(environment_, nullptr, object_, motion.at(contact_at))) << "step " << i;
    }
  }
  EXPECT_GT(hits, 2);
}

TEST_F(FlyQueries, ObstaclesSavedBesideTheIndexCount) {
  // A crate saved as a dynamic obstacle on the flight's way: fly --obstacles answers as brute
  // force over the scene and the placed crate.
  auto index = std::make_shared<const CollisionIndex>(folder_ / "scene.tpi");
  TriangleSoup crate;
  test::add_box(crate, {-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05});
  const Pose crate_pose{poses_[60].translation, {1, 0, 0, 0}};
  {
    DynamicObstacles obstacles(index);
    obstacles.insert(crate, crate_pose, "crate");
    obstacles.save(folder_ / "scene.obstacles");
  }
  fly("--obstacles " + path("scene.obstacles") + " --answers " + path("o.csv"));
  const auto rows = read_rows(folder_ / "o.csv", "step,collides");
  ASSERT_EQ(rows.size(), poses_.size());
  int crate_hits = 0;
  for (const auto& row : rows) {
    const Pose& pose = poses_[std::stoul(row[0])];
    // Touching the crate's faces, or wholly inside the (axis-aligned) crate.
    bool inside = true;
    for (const Vec3& v : object_.vertices) {
      const Vec3 w = apply_pose(pose, v);
      for (int a = 0; a < 3; ++a)
        inside = inside && std::fabs(w[a] - crate_pose.translation[a]) < 0.05;
    }
    const bool with_crate = inside || touches(crate, &crate_pose, object_, pose);
    crate_hits += with_crate;
    EXPECT_EQ(row[1], with_crate || touches(environment_, nullptr, object_, pose) ? "1" : "0")
        << "step " << row[0];
  }
  EXPECT_GT(crate_hits, 0);
  std::string out;
  std::ofstream(folder_ / "bad.obstacles") << "not an overlay\n";
  EXPECT_NE(
      test::run_cli("fly " + path("scene.tpi") + " --object " + path("object.ply") + " --path " +
                        path("flight3.csv") + " --obstacles " + path("bad.obstacles"),
                    out),
      0);
}

TEST_F(FlyQueries, SeveralObjectsAnswerAsBruteForce) {
  // The same object on two flights, and again on the first: objects 0 and 2 always coincide.
  std::string out;
  ASSERT_EQ(test::run_cli("fly " + path("scene.tpi") + " --object " + path("object.ply") +
                              " --path " + path("flight3.csv") + " --object " + path("object.ply") +
                              " --path " + path("flight4.csv") + " --object " + path("object.ply") +
                              " --path " + path("flight3.csv") + " --answers " + path("g.csv"),
                          out),
            0)
      << out;
  const auto other = read_poses(folder_ / "flight4.csv");
  const auto rows = read_rows(folder_ / "g.csv", "step,object,collides,environment,objects");
  ASSERT_EQ(rows.size(), 3 * poses_.size());
  int environment_hits = 0;
  for (const auto& row : rows) {
    const std::size_t step = std::stoul(row[0]), k = std::stoul(row[1]);
    const Pose& pose = k == 1 ? other[step] : poses_[step];
    const bool environment = touches(environment_, nullptr, object_, pose);
    environment_hits += environment;
    EXPECT_EQ(row[3], environment ? "1" : "0") << "step " << step << " object " << k;
    std::set<std::string> expected;
    for (std::size_t j = 0; j < 3; ++j)
      if (j != k && touches(object_, j == 1 ? &other[step] : &poses_[step], object_, pose))
        expected.insert(std::to_string(j));
    std::set<std::string> listed;
    std::stringstream list(row.size() > 4 ? row[4] : "");
    for (std::string item; std::getline(list, item, ';');) listed.insert(item);
    EXPECT_EQ(listed, expected) << "step " << step << " object " << k;
    EXPECT_EQ(row[2], environment || !expected.empty() ? "1" : "0");
  }
  EXPECT_GT(environment_hits, 2);
  // Mismatched counts and single-object queries are refused.
  EXPECT_NE(test::run_cli("fly " + path("scene.tpi") + " --object " + path("object.ply") +
                              " --object " + path("object.ply") + " --path " + path("flight3.csv"),
                          out),
            0);
  EXPECT_NE(test::run_cli("fly " + path("scene.tpi") + " --object " + path("object.ply") +
                              " --path " + path("flight3.csv") + " --object " + path("object.ply") +
                              " --path " + path("flight4.csv") + " --query distance",
                          out),
            0);
}

// Every answer file names a step's site alike: the kind (surface, near, solid, object_inside,
// obstacle_inside), the environment part and the flying part by id, name and path, and both
// points. Five hand-placed poses of a two-part object: inside the tower, through the floor's
// top, 0.01 above it, around a small cube, and free; checked against CGAL.
TEST_F(FlyQueries, AnswerFilesNameTheSameSites) {
  TriangleSoup scene;
  test::add_box(scene, {0.0, 0.0, 0.0}, {1.0, 1.0, 0.05});             // box0: the floor
  test::add_box(scene, {0.2, 0.2, 0.05}, {0.3, 0.3, 0.4});             // box1: a tower
  test::add_box(scene, {0.795, 0.795, 0.495}, {0.805, 0.805, 0.505});  // box2: a small cube
  write_mesh(folder_ / "sites.ply", scene);
  TriangleSoup pair;
  test::add_box(pair, {-0.04, -0.03, -0.02}, {-0.005, 0.03, 0.02});
  test::add_box(pair, {0.005, -0.03, -0.02}, {0.04, 0.03, 0.02});
  pair.part_names = {"left", "right"};
  write_mesh(folder_ / "pair.ply", pair);
  const std::vector<Pose> poses = {{{0.25, 0.25, 0.2}, {1, 0, 0, 0}},
                                   {{0.5, 0.5, 0.06}, {1, 0, 0, 0}},
                                   {{0.5, 0.5, 0.08}, {1, 0, 0, 0}},
                                   {{0.8 - 0.0225, 0.8, 0.5}, {1, 0, 0, 0}},
                                   {{0.5, 0.9, 0.6}, {1, 0, 0, 0}}};
  {
    std::ofstream out(folder_ / "sites.csv");
    out.precision(17);
    out << "tx,ty,tz,qw,qx,qy,qz\n";
    for (const Pose& p : poses)
      out << p.translation[0] << ',' << p.translation[1] << ',' << p.translation[2] << ",1,0,0,0\n";
  }
  std::string out;
  ASSERT_EQ(test::run_cli("preprocess " + path("sites.ply") + " -o " + path("sites.tpi"), out), 0)
      << out;
  const std::string flight =
      "fly " + path("sites.tpi") + " --object " + path("pair.ply") + " --path " + path("sites.csv");
  ASSERT_EQ(test::run_cli(flight + " --all-contacts --contacts " + path("listed.csv"), out), 0)
      << out;
  for (const std::string query : {"contacts", "distance", "toi"})
    ASSERT_EQ(test::run_cli(
                  flight + " --query " + query + " --answers " + path("q-" + query + ".csv"), out),
              0)
        << out;
  ASSERT_EQ(test::run_cli(flight + " --query contacts --accuracy clearance:0.02 --answers " +
                              path("near.csv"),
                          out),
            0)
      << out;
  const Table listed = read_table(folder_ / "listed.csv"),
              contacts = read_table(folder_ / "q-contacts.csv"),
              distance = read_table(folder_ / "q-distance.csv"),
              impact = read_table(folder_ / "q-toi.csv"), near = read_table(folder_ / "near.csv");
  for (const Table* table : {&listed, &contacts, &distance, &impact, &near}) {
    ASSERT_GE(table->header.size(), 17u);
    EXPECT_EQ(std::vector<std::string>(table->header.begin(), table->header.begin() + 17),
              split_fields(kSite));
  }

  // Both contact files list the same sites: the containments too.
  auto sites = [](const Table& table) {
    std::multiset<std::string> found;
    for (std::size_t r = 0; r < table.rows.size(); ++r)
      found.insert(table.at(r, "step") + ' ' + table.at(r, "kind") + ' ' +
                   table.at(r, "part_name") + ' ' + table.at(r, "object_part_name") + ' ' +
                   table.at(r, "environment_triangle") + ' ' + table.at(r, "object_triangle"));
    return found;
  };
  EXPECT_EQ(sites(listed), sites(contacts));
  std::map<std::string, std::set<std::string>> kinds;  // step -> kind + part name
  for (std::size_t r = 0; r < listed.rows.size(); ++r)
    kinds[listed.at(r, "step")].insert(listed.at(r, "kind") + ' ' + listed.at(r, "part_name"));
  EXPECT_EQ(kinds["0"], std::set<std::string>{"object_inside box1"});
  EXPECT_EQ(kinds["1"], std::set<std::string>{"surface box0"});
  EXPECT_EQ(kinds.count("2"), 0u);
  EXPECT_EQ(kinds["3"], std::set<std::string>{"obstacle_inside box2"});
  EXPECT_EQ(kinds.count("4"), 0u);
  for (std::size_t r = 0; r < listed.rows.size(); ++r) {
    if (listed.at(r, "kind") != "surface") {
      EXPECT_EQ(listed.at(r, "object_part_name"), "");
      EXPECT_EQ(listed.at(r, "environment_x"), "");
      continue;
    }
    // The flying part is the one that holds the object triangle; the point lies on both triangles.
    const std::size_t o = std::stoul(listed.at(r, "object_triangle"));
    EXPECT_EQ(listed.at(r, "object_part_name"), o < 12 ? "left" : "right");
    EXPECT_EQ(listed.at(r, "object_part"), o < 12 ? "0" : "1");
    const Pose& pose = poses[std::stoul(listed.at(r, "step"))];
    const auto e =
        triangle<Exact>(scene.corners(std::stoull(listed.at(r, "environment_triangle"))));
    const auto t = triangle<Exact>(placed(pair, o, pose));
    const Vec3 p = point_of(listed, r, "environment");
    const Exact::Point_3 q(p[0], p[1], p[2]);
    EXPECT_LT(CGAL::to_double(CGAL::squared_distance(q, e)), 1e-24);
    EXPECT_LT(CGAL::to_double(CGAL::squared_distance(q, t)), 1e-24);
    EXPECT_EQ(point_of(listed, r, "object"), p);
  }

  // Distance: the containments touch with their part named; the gap of 0.01 is a near pair.
  ASSERT_EQ(distance.rows.size(), poses.size());
  EXPECT_EQ(distance.at(0, "kind"), "object_inside");
  EXPECT_EQ(distance.at(0, "part_name"), "box1");
  EXPECT_EQ(distance.at(0, "separation"), "touching");
  EXPECT_EQ(distance.at(1, "kind"), "surface");
  EXPECT_EQ(distance.at(1, "part_name"), "box0");
  EXPECT_EQ(distance.at(2, "kind"), "near");
  EXPECT_EQ(distance.at(2, "separation"), "apart");
  EXPECT_NEAR(std::stod(distance.at(2, "distance")), 0.01, 1e-12);
  EXPECT_NEAR(point_of(distance, 2, "object")[2] - point_of(distance, 2, "environment")[2], 0.01,
              1e-12);
  EXPECT_EQ(distance.at(3, "kind"), "obstacle_inside");
  EXPECT_EQ(distance.at(3, "part_name"), "box2");
  EXPECT_EQ(distance.at(4, "kind"), "near");

  // Time of impact: step 0 (the pose alone) hits by containment, and every hit names its site.
  ASSERT_EQ(impact.rows.size(), poses.size());
  EXPECT_EQ(impact.at(0, "impact"), "hit");
  EXPECT_EQ(impact.at(0, "kind"), "object_inside");
  EXPECT_EQ(impact.at(0, "part_name"), "box1");
  for (std::size_t r = 0; r < impact.rows.size(); ++r) {
    EXPECT_EQ(impact.at(r, "impact") == "hit", impact.at(r, "kind") != "") << r;
    if (impact.at(r, "kind") == "surface") {
      EXPECT_NE(impact.at(r, "object_part_name"), "") << r;
    }
  }

  // Under clearance:0.02, the pose 0.01 above the floor has near pairs only (and the other
  // poses have some beside their contacts): their triangles do not meet, and their points are
  // at most 0.02 apart.
  std::size_t near_pairs = 0;
  for (std::size_t r = 0; r < near.rows.size(); ++r) {
    if (near.at(r, "kind") != "near") continue;
    near_pairs += near.at(r, "step") == "2" ? 1 : 0;
    EXPECT_EQ(near.at(r, "shape"), "none");
    const Pose& pose = poses[std::stoul(near.at(r, "step"))];
    const auto e = triangle<Exact>(scene.corners(std::stoull(near.at(r, "environment_triangle"))));
    const auto t = triangle<Exact>(placed(pair, std::stoul(near.at(r, "object_triangle")), pose));
    EXPECT_FALSE(CGAL::do_intersect(e, t));
    const Vec3 a = point_of(near, r, "environment"), b = point_of(near, r, "object");
    const double gap = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                                 (a[2] - b[2]) * (a[2] - b[2]));
    EXPECT_GE(gap, near.at(r, "step") == "2" ? 0.01 - 1e-12 : 1e-12);
    EXPECT_LE(gap, 0.02 + 1e-12);
  }
  EXPECT_GT(near_pairs, 0u);
}

}  // namespace
}  // namespace tetrapage
