// `tetrapage fly --query contacts|distance|toi` and fly with several objects, end to end,
// against CGAL: every contact row's points lie on both triangles, which do meet; every distance
// row's value is CGAL's exact distance over all pairs, within its bracket; every toi hit's
// contact pose collides and the motion is free before it at sampled times; a group's rows are
// the brute-force object/environment and object/object answers.
#include <gtest/gtest.h>
#include <unistd.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "BoxSoup.h"
#include "RunCli.h"
#include "tetrapage/formats/MeshReader.h"
#include "tetrapage/formats/MeshWriter.h"
#include "tetrapage/formats/Pose.h"
#include "tetrapage/runtime/DynamicObstacles.h"
#include "tetrapage/runtime/PoseMotion.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
using Inexact = CGAL::Exact_predicates_inexact_constructions_kernel;

std::vector<std::vector<std::string>> read_rows(const fs::path& path, const std::string& header) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, header) << path;
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> fields(1);
    for (const char c : line) {
      if (c == ',')
        fields.emplace_back();
      else
        fields.back() += c;
    }
    rows.push_back(fields);
  }
  return rows;
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
    ASSERT_EQ(test::run_cli("preprocess " + path("scene.ply") + " -o " + path("scene.tpi"), out), 0) << out;
    for (const char* seed : {"3", "4"})
      ASSERT_EQ(test::run_cli("generate flight --env " + path("scene.ply") + " --object " + path("object.ply") +
                                  " --steps 150 --displacement 0.02 --seed " + seed + " -o " +
                                  path(std::string("flight") + seed + ".csv"),
                              out),
                0)
          << out;
    poses_ = read_poses(folder_ / "flight3.csv");
  }
  void TearDown() override { fs::remove_all(folder_); }
  std::string path(const std::string& name) const { return (folder_ / name).string(); }
  std::string fly(const std::string& options) const {
    std::string out;
    EXPECT_EQ(test::run_cli("fly " + path("scene.tpi") + " --object " + path("object.ply") + " --path " +
                                path("flight3.csv") + " " + options,
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
  const auto rows = read_rows(folder_ / "d.csv",
                              "step,distance,x1,y1,z1,x2,y2,z2,part,environment_triangle,object_triangle,"
                              "separation,lower_bound,upper_bound");
  ASSERT_EQ(rows.size(), poses_.size());
  int apart = 0, touching = 0;
  for (const auto& row : rows) {
    ASSERT_EQ(row.size(), 14u);
    const Pose& pose = poses_[std::stoul(row[0])];
    Exact::FT least = -1;
    for (std::size_t e = 0; e < environment_.triangle_count(); ++e)
      for (std::size_t o = 0; o < object_.triangle_count(); ++o) {
        const Exact::FT d = CGAL::squared_distance(triangle<Exact>(environment_.corners(e)),
                                                   triangle<Exact>(placed(object_, o, pose)));
        if (least < 0 || d < least) least = d;
      }
    if (row[11] == "touching") {
      ++touching;
      EXPECT_EQ(least, 0) << "step " << row[0];
      continue;
    }
    ASSERT_EQ(row[11], "apart");
    ++apart;
    const Exact::FT lower(std::stod(row[12])), upper(std::stod(row[13]));
    EXPECT_LE(lower * lower, least) << "step " << row[0];
    EXPECT_GE(upper * upper, least) << "step " << row[0];
  }
  EXPECT_GT(apart, 20);
  EXPECT_GT(touching, 0);
}

TEST_F(FlyQueries, ContactRowsLieOnTrianglesThatMeet) {
  fly("--query contacts --answers " + path("c.csv"));
  const auto rows = read_rows(folder_ / "c.csv",
                              "step,part,part_name,environment_triangle,object_triangle,shape,x1,y1,z1,x2,y2,z2,"
                              "polygon,environment_nx,environment_ny,environment_nz,object_nx,object_ny,object_nz");
  ASSERT_GT(rows.size(), 5u);
  for (const auto& row : rows) {
    ASSERT_EQ(row.size(), 19u);
    const auto e = triangle<Exact>(environment_.corners(std::stoull(row[3])));
    const auto o = triangle<Exact>(placed(object_, std::stoul(row[4]), poses_[std::stoul(row[0])]));
    EXPECT_TRUE(CGAL::do_intersect(e, o));
    EXPECT_NE(row[5], "none");
    for (const int first : {6, 9}) {
      const Exact::Point_3 p(std::stod(row[first]), std::stod(row[first + 1]), std::stod(row[first + 2]));
      EXPECT_LT(CGAL::to_double(CGAL::squared_distance(p, e)), 1e-24);
      EXPECT_LT(CGAL::to_double(CGAL::squared_distance(p, o)), 1e-24);
    }
  }
}

TEST_F(FlyQueries, ImpactRowsBracketTheFirstContact) {
  fly("--query toi --toi-tolerance 1e-3 --answers " + path("t.csv"));
  const auto rows = read_rows(folder_ / "t.csv",
                              "step,impact,free_until,contact_at,part,environment_triangle,object_triangle,iterations");
  ASSERT_EQ(rows.size(), poses_.size());
  int hits = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto& row = rows[i];
    ASSERT_NE(row[1], "unresolved");
    const PoseMotion motion(poses_[i - 1], poses_[i]);
    const double free_until = std::stod(row[2]), contact_at = std::stod(row[3]);
    for (int s = 0; s < 20 && free_until > 0; ++s)
      EXPECT_FALSE(touches(environment_, nullptr, object_, motion.at(free_until * s / 20.0))) << "step " << i;
    if (row[1] == "hit") {
      ++hits;
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
      for (int a = 0; a < 3; ++a) inside = inside && std::fabs(w[a] - crate_pose.translation[a]) < 0.05;
    }
    const bool with_crate = inside || touches(crate, &crate_pose, object_, pose);
    crate_hits += with_crate;
    EXPECT_EQ(row[1], with_crate || touches(environment_, nullptr, object_, pose) ? "1" : "0") << "step " << row[0];
  }
  EXPECT_GT(crate_hits, 0);
  std::string out;
  std::ofstream(folder_ / "bad.obstacles") << "not an overlay\n";
  EXPECT_NE(test::run_cli("fly " + path("scene.tpi") + " --object " + path("object.ply") + " --path " +
                              path("flight3.csv") + " --obstacles " + path("bad.obstacles"),
                          out),
            0);
}

TEST_F(FlyQueries, SeveralObjectsAnswerAsBruteForce) {
  // The same object on two flights, and again on the first: objects 0 and 2 always coincide.
  std::string out;
  ASSERT_EQ(test::run_cli("fly " + path("scene.tpi") + " --object " + path("object.ply") + " --path " +
                              path("flight3.csv") + " --object " + path("object.ply") + " --path " +
                              path("flight4.csv") + " --object " + path("object.ply") + " --path " +
                              path("flight3.csv") + " --answers " + path("g.csv"),
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
  EXPECT_NE(test::run_cli("fly " + path("scene.tpi") + " --object " + path("object.ply") + " --object " +
                              path("object.ply") + " --path " + path("flight3.csv"),
                          out),
            0);
  EXPECT_NE(test::run_cli("fly " + path("scene.tpi") + " --object " + path("object.ply") + " --path " +
                              path("flight3.csv") + " --object " + path("object.ply") + " --path " +
                              path("flight4.csv") + " --query distance",
                          out),
            0);
}

}  // namespace
}  // namespace tetrapage
