// Parts by name from the assembly to the answers: the index keeps each part's name, instance
// path and triangles; a stored triangle is found by its id; `fly --contacts` writes every
// contact pair with its part and a point where the two triangles meet. The oracle is brute
// force: every environment triangle against every placed object triangle with CGAL's exact
// predicates, and the parts read back from the input soup.

#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "BoxSoup.h"
#include "RunCli.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/index/IndexSchema.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/tools/AnswerFile.h"

namespace tetrapage {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

std::filesystem::path fresh_folder(const std::string& name) {
  const auto folder =
      std::filesystem::path(TETRAPAGE_TEST_TMP) / (name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

// A plate, three pins placed on it, and a frame: parts with names, one placed several times.
std::filesystem::path write_assembly(const std::filesystem::path& folder) {
  TriangleSoup plate, pin, frame;
  test::add_box(plate, {0.0, 0.0, 0.0}, {1.0, 1.0, 0.05});
  test::add_box(pin, {-0.03, -0.03, 0.0}, {0.03, 0.03, 0.3});
  test::add_box(frame, {0.0, 0.0, 0.6}, {1.0, 0.08, 0.68});
  test::add_box(frame, {0.0, 0.92, 0.6}, {1.0, 1.0, 0.68});
  write_mesh(folder / "plate.ply", plate);
  write_mesh(folder / "pin.ply", pin);
  write_mesh(folder / "frame.obj", frame);
  std::ofstream(folder / "assembly.json") << R"({ "units": "mm", "parts": [
    { "name": "plate", "file": "plate.ply" },
    { "name": "pin", "file": "pin.ply", "instances": [
        { "translation": [0.25, 0.3, 0.05] }, { "translation": [0.5, 0.6, 0.05] },
        { "translation": [0.75, 0.4, 0.05], "rotation": [0.9238795, 0, 0, 0.3826834] } ] },
    { "name": "frame", "file": "frame.obj" } ] })";
  return folder / "assembly.json";
}

struct ContactRow {
  std::uint64_t step, environment_triangle;
  std::uint32_t part, object_triangle;
  std::string name, path;
  Vec3 point;
};

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"')
      fields.back() += '"', ++i;
    else if (c == '"')
      quoted = !quoted;
    else if (c == ',' && !quoted)
      fields.emplace_back();
    else
      fields.back() += c;
  }
  return fields;
}

std::vector<ContactRow> read_contacts(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line,
            "step,kind,part,part_name,part_path,dynamic_part,environment_triangle,object_part,"
            "object_part_name,object_part_path,object_triangle,environment_x,environment_y,"
            "environment_z,object_x,object_y,object_z");
  std::vector<ContactRow> rows;
  while (std::getline(in, line)) {
    const auto f = split_csv(line);
    EXPECT_EQ(f.size(), 17u) << line;
    if (f.size() != 17 || f[1] != "surface") continue;
    rows.push_back({std::stoull(f[0]),
                    std::stoull(f[6]),
                    std::uint32_t(std::stoul(f[2])),
                    std::uint32_t(std::stoul(f[10])),
                    f[3],
                    f[4],
                    {std::stod(f[11]), std::stod(f[12]), std::stod(f[13])}});
  }
  return rows;
}

Kernel::Triangle_3 to_kernel(const std::array<Vec3, 3>& t) {
  return {{t[0][0], t[0][1], t[0][2]}, {t[1][0], t[1][1], t[1][2]}, {t[2][0], t[2][1], t[2][2]}};
}

TEST(PartsAndContacts, ContactsNameTheirPartsAndMatchBruteForce) {
  const auto folder = fresh_folder("contacts");
  const auto manifest = write_assembly(folder);
  TriangleSoup object;
  test::add_box(object, {-0.04, -0.04, -0.04}, {0.04, 0.04, 0.04});
  write_mesh(folder / "object.ply", object);
  std::string out;
  ASSERT_EQ(
      test::run_cli("preprocess " + manifest.string() + " -o " + (folder / "a.tpi").string(), out),
      0)
      << out;
  ASSERT_EQ(
      test::run_cli(
          "generate flight --env " + manifest.string() + " --object " +
              (folder / "object.ply").string() + " --steps 400 --seed 3 --displacement 0.02 -o " +
              (folder / "flight.csv").string() + " --answers " + (folder / "answers.csv").string(),
          out),
      0)
      << out;
  ASSERT_EQ(
      test::run_cli(
          "fly " + (folder / "a.tpi").string() + " --object " + (folder / "object.ply").string() +
              " --path " + (folder / "flight.csv").string() + " --all-contacts --contacts " +
              (folder / "contacts.csv").string() + " --check " + (folder / "answers.csv").string(),
          out),
      0)
      << out;

  const TriangleSoup environment = load_inputs({manifest});
  const std::vector<Pose> poses = read_poses(folder / "flight.csv");
  const auto rows = read_contacts(folder / "contacts.csv");
  std::map<std::uint64_t, std::set<std::pair<std::uint64_t, std::uint32_t>>> written;
  for (const ContactRow& row : rows) {
    ASSERT_LT(row.environment_triangle, environment.triangle_count());
    const std::uint32_t part = environment.part_of[row.environment_triangle];
    EXPECT_EQ(row.part, part);
    EXPECT_EQ(row.name, environment.part_names[part]);
    EXPECT_EQ(row.path, environment.part_path(part));
    written[row.step].insert({row.environment_triangle, row.object_triangle});
    // The point lies on both triangles (up to its rounding to double).
    std::array<Vec3, 3> placed = object.corners(row.object_triangle);
    for (Vec3& p : placed) p = apply_pose(poses[row.step], p);
    const Kernel::Point_3 point(row.point[0], row.point[1], row.point[2]);
    EXPECT_LT(
        CGAL::squared_distance(point, to_kernel(environment.corners(row.environment_triangle))),
        1e-24);
    EXPECT_LT(CGAL::squared_distance(point, to_kernel(placed)), 1e-24);
  }
  std::size_t steps_with_contacts = 0;
  for (std::size_t step = 0; step < poses.size(); ++step) {
    std::set<std::pair<std::uint64_t, std::uint32_t>> expected;
    for (std::uint32_t o = 0; o < object.triangle_count(); ++o) {
      std::array<Vec3, 3> placed = object.corners(o);
      for (Vec3& p : placed) p = apply_pose(poses[step], p);
      const auto placed_triangle = to_kernel(placed);
      for (std::uint64_t e = 0; e < environment.triangle_count(); ++e)
        if (CGAL::do_intersect(placed_triangle, to_kernel(environment.corners(e))))
          expected.insert({e, o});
    }
    steps_with_contacts += !expected.empty();
    EXPECT_EQ(written[step], expected) << "step " << step;
  }
  EXPECT_GT(steps_with_contacts, 5u);  // the flight touches the parts
}

TEST(PartsAndContacts, TheIndexKeepsPartsAndFindsTrianglesById) {
  const auto folder = fresh_folder("parts");
  const auto manifest = write_assembly(folder);
  std::string out;
  ASSERT_EQ(test::run_cli("preprocess " + manifest.string() + " -o " + (folder / "a.tpi").string() +
                              " --region-triangles 8",
                          out),
            0)
      << out;
  const TriangleSoup soup = load_inputs({manifest});
  {
    const CollisionIndex index(folder / "a.tpi");
    EXPECT_EQ(index.header().length_unit, "mm");
    ASSERT_TRUE(index.parts().named());
    ASSERT_EQ(index.parts().count(), soup.part_count());
    std::vector<std::uint64_t> triangles(soup.part_count(), 0);
    for (const auto part : soup.part_of) ++triangles[part];
    for (std::uint32_t p = 0; p < soup.part_count(); ++p) {
      EXPECT_EQ(index.parts().name(p), soup.part_names[p]);
      EXPECT_EQ(index.parts().path(p), soup.part_path(p));
      EXPECT_EQ(index.parts().triangles(p), triangles[p]);
    }
    for (std::uint64_t id = 0; id < soup.triangle_count(); ++id) {
      const auto stored = index.stored_triangle(id);
      ASSERT_TRUE(stored) << id;
      EXPECT_EQ(stored->corners, soup.corners(id)) << id;  // exact storage decodes the input
      EXPECT_EQ(index.component_part(stored->component), soup.part_of[id]) << id;
    }
    EXPECT_FALSE(index.stored_triangle(soup.triangle_count()));
    ASSERT_EQ(
        test::run_cli("inspect " + (folder / "a.tpi").string() + " --stabbing-segments 0 --parts 0",
                      out),
        0);
    EXPECT_NE(out.find("unit: mm"), std::string::npos) << out;
    for (std::uint32_t p = 0; p < soup.part_count(); ++p)
      EXPECT_NE(out.find(soup.part_path(p) + " (" + soup.part_names[p] + "), " +
                         std::to_string(triangles[p]) + " triangles"),
                std::string::npos)
          << out;
  }
  // An index from before the part tables: its parts are "part K", and ids are still found.
  namespace schema = index_schema;
  const auto old_index = folder / "old.tpi";
  std::filesystem::copy_file(folder / "a.tpi", old_index);
  {
    const hid_t file = H5Fopen(old_index.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    for (const auto table : {schema::table::part_name_offsets, schema::table::part_name_bytes,
                             schema::table::part_path_offsets, schema::table::part_path_bytes,
                             schema::table::part_triangles, schema::table::shard_id_ranges})
      EXPECT_GE(H5Ldelete(file, schema::table_path(table).c_str(), H5P_DEFAULT), 0);
    H5Fclose(file);
  }
  {
    const CollisionIndex index(old_index);
    EXPECT_FALSE(index.parts().named());
    EXPECT_EQ(index.parts().name(1), "part 1");
    const auto stored = index.stored_triangle(5);
    ASSERT_TRUE(stored);
    EXPECT_EQ(stored->corners, soup.corners(5));
  }
  // Some part tables without the others: refused, asking for a rebuild.
  {
    const hid_t file = H5Fopen((folder / "a.tpi").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    EXPECT_GE(
        H5Ldelete(file, schema::table_path(schema::table::part_triangles).c_str(), H5P_DEFAULT), 0);
    H5Fclose(file);
  }
  try {
    const CollisionIndex index(folder / "a.tpi");
    ADD_FAILURE() << "opened";
  } catch (const FormatError& error) {
    EXPECT_NE(std::string(error.what()).find("rebuild the index"), std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace tetrapage
