// The C API (tetrapage.h): every function, its error paths (missing and corrupted files, null
// arguments, NaN poses, invalid accuracies), and its answers against the C++ FlyingObject and
// a brute-force oracle (every environment triangle against every object triangle, exactly) on
// random poses. The index is built once by preprocess from a few hundred triangles (stored in
// double precision, so the stored coordinates are the input's). The deprecated calls of the first
// release are covered too, against the calls that replace them.

#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"

// The deprecated calls stay tested until they go.
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#include "tetrapage/runtime/geometry/Accuracy.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tetrapage.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

constexpr std::uint64_t kBudget = std::uint64_t(64) << 20;

/// Uniform doubles in [0, 1) from a fixed-seed generator (the same on every platform).
class Uniform {
 public:
  explicit Uniform(std::uint64_t seed) : engine_(seed) {}
  double operator()() { return double(engine_() >> 11) * 0x1.0p-53; }
  double operator()(double lo, double hi) { return lo + (hi - lo) * (*this)(); }

 private:
  std::mt19937_64 engine_;
};

/// The surface of an axis-aligned box, each face split into n x n squares (12 n^2 triangles).
void add_box(TriangleSoup& soup, const Vec3& lo, const Vec3& hi, int n) {
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      const auto base = std::uint32_t(soup.vertices.size());
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
          Vec3 p;
          p[axis] = side ? hi[axis] : lo[axis];
          p[u] = lo[u] + (hi[u] - lo[u]) * i / n;
          p[v] = lo[v] + (hi[v] - lo[v]) * j / n;
          soup.vertices.push_back(p);
        }
      const auto at = [&](int i, int j) { return base + std::uint32_t(i * (n + 1) + j); };
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          soup.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
          soup.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
          soup.part_of.push_back(0);
          soup.part_of.push_back(0);
        }
    }
  }
}

/// A small closed object: a box of 12 triangles, 0.3 x 0.2 x 0.1, centred at its origin.
TriangleSoup small_object() {
  TriangleSoup object;
  object.part_names = {"object"};
  add_box(object, {-0.15, -0.1, -0.05}, {0.15, 0.1, 0.05}, 1);
  return object;
}

std::vector<double> flat_vertices(const TriangleSoup& soup) {
  std::vector<double> out;
  for (const auto& v : soup.vertices) out.insert(out.end(), v.begin(), v.end());
  return out;
}

std::vector<std::uint32_t> flat_triangles(const TriangleSoup& soup) {
  std::vector<std::uint32_t> out;
  for (const auto& t : soup.triangles) out.insert(out.end(), t.begin(), t.end());
  return out;
}

/// A random pose: translation in [-0.5, 4.5]^3 (around and inside the environment), a uniform
/// unit quaternion.
std::array<double, 7> random_pose(Uniform& uniform) {
  std::array<double, 7> pose{};
  for (int a = 0; a < 3; ++a) pose[a] = uniform(-0.5, 4.5);
  double norm = 0;
  do {
    norm = 0;
    for (int c = 3; c < 7; ++c) {
      pose[c] = uniform(-1, 1);
      norm += pose[c] * pose[c];
    }
  } while (norm < 0.01 || norm > 1);
  for (int c = 3; c < 7; ++c) pose[c] /= std::sqrt(norm);
  return pose;
}

Pose to_pose(const std::array<double, 7>& p) {
  Pose pose;
  pose.translation = {p[0], p[1], p[2]};
  pose.rotation = {p[3], p[4], p[5], p[6]};
  return pose;
}

using ContactKey = std::tuple<std::uint32_t, std::uint64_t, std::uint32_t>;

std::set<ContactKey> contact_set(const std::vector<tetrapage_hit>& contacts) {
  std::set<ContactKey> out;
  for (const auto& c : contacts)
    out.emplace(c.environment_part, c.environment_triangle, c.object_triangle);
  return out;
}

std::set<ContactKey> contact_set(const std::vector<tetrapage_contact>& contacts) {
  std::set<ContactKey> out;
  for (const auto& c : contacts) out.emplace(c.environment_part, c.environment_triangle, c.object_triangle);
  return out;
}

std::set<ContactKey> contact_set(const std::vector<Contact>& contacts) {
  std::set<ContactKey> out;
  for (const auto& c : contacts) out.emplace(c.environment_part, c.environment_triangle, c.object_triangle);
  return out;
}

class CApiTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // ctest runs each test in its own process, two at a time: one folder per process, or two
    // set-ups write the same files at once and a failed set-up skips the tests silently.
    folder_ = fs::path(TETRAPAGE_TEST_TMP) / ("capi-" + std::to_string(::getpid()));
    fs::remove_all(folder_);
    fs::create_directories(folder_);
    // Two subdivided boxes and a thin slab between them: 2 * 192 + 48 = 432 triangles, on
    // dyadic coordinates.
    TriangleSoup environment;
    environment.part_names = {"environment"};
    add_box(environment, {0, 0, 0}, {1.5, 1.5, 1.5}, 4);
    add_box(environment, {2.5, 2.5, 2.5}, {4, 4, 4}, 4);
    add_box(environment, {0.5, 2.5, 1.75}, {3.5, 3.5, 2}, 2);
    environment_ = environment;
    write_mesh(folder_ / "environment.obj", environment);
    // What preprocess stores: the triangles as read back (the ids are their order).
    environment_ = read_mesh(folder_ / "environment.obj");
    PreprocessOptions options;
    options.region_triangles = 40;
    options.threads = 1;
    options.precision = StoredPrecision::float64;
    index_path_ = folder_ / "environment.tpi";
    preprocess({folder_ / "environment.obj"}, index_path_, options);
    write_mesh(folder_ / "object.obj", small_object());
  }

  static void TearDownTestSuite() { fs::remove_all(folder_); }

  void SetUp() override {
    ASSERT_EQ(tetrapage_open(index_path_.c_str(), kBudget, &index_), TETRAPAGE_OK) << tetrapage_last_error();
  }
  void TearDown() override { tetrapage_close(index_); }

  tetrapage_object* create_object() {
    const auto object = small_object();
    const auto vertices = flat_vertices(object);
    const auto triangles = flat_triangles(object);
    tetrapage_object* created = nullptr;
    EXPECT_EQ(tetrapage_object_create(index_, vertices.data(), object.vertices.size(), triangles.data(),
                                      object.triangles.size(), &created),
              TETRAPAGE_OK)
        << tetrapage_last_error();
    return created;
  }

  /// Every (part, environment triangle, object triangle) pair that meets at `pose`.
  static std::set<ContactKey> brute_force(const std::array<double, 7>& p, const geometry::Accuracy& accuracy) {
    const TriangleSoup object = small_object();
    const Pose pose = to_pose(p);
    const auto rotation = rotation_matrix(pose.rotation);
    std::set<ContactKey> out;
    for (std::uint32_t o = 0; o < object.triangles.size(); ++o) {
      geometry::Triangle placed;
      for (int c = 0; c < 3; ++c)
        placed[c] = apply_pose(rotation, pose.translation, object.vertices[object.triangles[o][c]]);
      for (std::uint64_t e = 0; e < environment_.triangles.size(); ++e)
        if (geometry::triangles_collide(environment_.corners(e), placed, accuracy))
          out.emplace(environment_.part_of[e], e, o);
    }
    return out;
  }

  static inline fs::path folder_;
  static inline fs::path index_path_;
  static inline TriangleSoup environment_;
  tetrapage_index* index_ = nullptr;
};

// The library reports the version its headers carry, and the macros agree with each other.
TEST(CApiVersion, LibraryVersionIsTheHeaders) {
  ASSERT_NE(tetrapage_version(), nullptr);
  EXPECT_STREQ(tetrapage_version(), TETRAPAGE_VERSION_STRING);
  EXPECT_EQ(std::to_string(TETRAPAGE_VERSION_MAJOR) + "." +
                std::to_string(TETRAPAGE_VERSION_MINOR) + "." +
                std::to_string(TETRAPAGE_VERSION_PATCH),
            TETRAPAGE_VERSION_STRING);
  EXPECT_EQ(TETRAPAGE_VERSION, TETRAPAGE_VERSION_MAJOR * 10000 + TETRAPAGE_VERSION_MINOR * 100 +
                                   TETRAPAGE_VERSION_PATCH);
}

TEST_F(CApiTest, StatusStringsAreDistinctAndNeverNull) {
  std::set<std::string> names;
  for (int s = TETRAPAGE_OK; s <= TETRAPAGE_ERROR_STALE_HANDLE; ++s) {
    const char* name = tetrapage_status_string(static_cast<tetrapage_status>(s));
    ASSERT_NE(name, nullptr);
    EXPECT_TRUE(names.insert(name).second) << "status " << s << " repeats " << name;
  }
  EXPECT_STREQ(tetrapage_status_string(static_cast<tetrapage_status>(99)), "unknown status");
}

TEST_F(CApiTest, MissingFileIsAnIoErrorNamingTheFile) {
  const fs::path missing = folder_ / "no-such-index.tpi";
  tetrapage_index* index = reinterpret_cast<tetrapage_index*>(&index_);  // must be reset
  EXPECT_EQ(tetrapage_open(missing.c_str(), kBudget, &index), TETRAPAGE_ERROR_IO);
  EXPECT_EQ(index, nullptr);
  EXPECT_NE(std::string(tetrapage_last_error()).find(missing.string()), std::string::npos)
      << tetrapage_last_error();
  // A folder is no index either.
  EXPECT_EQ(tetrapage_open(folder_.c_str(), kBudget, &index), TETRAPAGE_ERROR_IO);
}

TEST_F(CApiTest, CorruptedFilesAreFormatErrors) {
  const fs::path garbage = folder_ / "garbage.tpi";
  std::ofstream(garbage) << "this is not an HDF5 file at all\n";
  tetrapage_index* index = nullptr;
  EXPECT_EQ(tetrapage_open(garbage.c_str(), kBudget, &index), TETRAPAGE_ERROR_FORMAT);
  EXPECT_EQ(index, nullptr);
  EXPECT_NE(std::string(tetrapage_last_error()).find(garbage.string()), std::string::npos)
      << tetrapage_last_error();

  // The real index cut in half.
  const fs::path truncated = folder_ / "truncated.tpi";
  fs::copy_file(index_path_, truncated, fs::copy_options::overwrite_existing);
  fs::resize_file(truncated, fs::file_size(index_path_) / 2);
  EXPECT_EQ(tetrapage_open(truncated.c_str(), kBudget, &index), TETRAPAGE_ERROR_FORMAT)
      << tetrapage_last_error();
  EXPECT_EQ(index, nullptr);
}

TEST_F(CApiTest, ZeroBudgetIsAnInputError) {
  tetrapage_index* index = nullptr;
  EXPECT_EQ(tetrapage_open(index_path_.c_str(), 0, &index), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(index, nullptr);
  EXPECT_STRNE(tetrapage_last_error(), "");
}

TEST_F(CApiTest, SuccessClearsTheMessageAndMessagesArePerThread) {
  tetrapage_index* index = nullptr;
  ASSERT_EQ(tetrapage_open(nullptr, kBudget, &index), TETRAPAGE_ERROR_INVALID_ARGUMENT);
  const std::string message = tetrapage_last_error();
  EXPECT_NE(message.find("path"), std::string::npos) << message;
  std::string other_thread_message = "unset";
  std::thread([&] { other_thread_message = tetrapage_last_error(); }).join();
  EXPECT_EQ(other_thread_message, "");
  EXPECT_EQ(tetrapage_last_error(), message);
  double lo[3], hi[3];
  ASSERT_EQ(tetrapage_index_bounds(index_, lo, hi), TETRAPAGE_OK);
  EXPECT_STREQ(tetrapage_last_error(), "");
}

TEST_F(CApiTest, NullArgumentsAreReportedNotDereferenced) {
  const auto object_soup = small_object();
  const auto vertices = flat_vertices(object_soup);
  const auto triangles = flat_triangles(object_soup);
  const std::size_t vertex_count = object_soup.vertices.size(), triangle_count = object_soup.triangles.size();
  constexpr auto invalid = TETRAPAGE_ERROR_INVALID_ARGUMENT;
  const auto names = [](const char* word) {
    return std::string(tetrapage_last_error()).find(word) != std::string::npos;
  };
  tetrapage_index* index = nullptr;
  EXPECT_EQ(tetrapage_open(index_path_.c_str(), kBudget, nullptr), invalid);
  EXPECT_TRUE(names("index")) << tetrapage_last_error();
  EXPECT_EQ(tetrapage_open(nullptr, kBudget, &index), invalid);
  double lo[3], hi[3];
  EXPECT_EQ(tetrapage_index_bounds(nullptr, lo, hi), invalid);
  EXPECT_EQ(tetrapage_index_bounds(index_, nullptr, hi), invalid);
  EXPECT_EQ(tetrapage_index_bounds(index_, lo, nullptr), invalid);

  tetrapage_object* object = nullptr;
  EXPECT_EQ(tetrapage_object_create(nullptr, vertices.data(), vertex_count, triangles.data(), triangle_count, &object),
            invalid);
  EXPECT_EQ(tetrapage_object_create(index_, nullptr, vertex_count, triangles.data(), triangle_count, &object),
            invalid);
  EXPECT_TRUE(names("vertices")) << tetrapage_last_error();
  EXPECT_EQ(tetrapage_object_create(index_, vertices.data(), vertex_count, nullptr, triangle_count, &object),
            invalid);
  EXPECT_TRUE(names("triangles")) << tetrapage_last_error();
  EXPECT_EQ(tetrapage_object_create(index_, vertices.data(), vertex_count, triangles.data(), triangle_count, nullptr),
            invalid);
  EXPECT_EQ(tetrapage_object_create_from_file(nullptr, (folder_ / "object.obj").c_str(), &object), invalid);
  EXPECT_EQ(tetrapage_object_create_from_file(index_, nullptr, &object), invalid);
  EXPECT_EQ(tetrapage_object_create_from_file(index_, (folder_ / "object.obj").c_str(), nullptr), invalid);
  EXPECT_EQ(object, nullptr);

  tetrapage_accuracy accuracy;
  double parameter;
  EXPECT_EQ(tetrapage_parse_accuracy(nullptr, &accuracy, &parameter), invalid);
  EXPECT_EQ(tetrapage_parse_accuracy("exact", nullptr, &parameter), invalid);
  EXPECT_EQ(tetrapage_parse_accuracy("exact", &accuracy, nullptr), invalid);

  object = create_object();
  ASSERT_NE(object, nullptr);
  const double pose[7] = {0.75, 0.75, 0.75, 1, 0, 0, 0};
  int collides = 0;
  EXPECT_EQ(tetrapage_query(nullptr, pose, TETRAPAGE_ACCURACY_EXACT, 0, 0, &collides), invalid);
  EXPECT_EQ(tetrapage_query(object, nullptr, TETRAPAGE_ACCURACY_EXACT, 0, 0, &collides), invalid);
  EXPECT_TRUE(names("pose")) << tetrapage_last_error();
  EXPECT_EQ(tetrapage_query(object, pose, TETRAPAGE_ACCURACY_EXACT, 0, 0, nullptr), invalid);
  std::size_t count = 0, written = 0;
  tetrapage_contact contact;
  tetrapage_query_info info;
  EXPECT_EQ(tetrapage_contact_count(nullptr, &count), invalid);
  EXPECT_EQ(tetrapage_contact_count(object, nullptr), invalid);
  EXPECT_EQ(tetrapage_get_contacts(nullptr, &contact, 1, &written), invalid);
  EXPECT_EQ(tetrapage_get_contacts(object, nullptr, 1, &written), invalid);
  EXPECT_EQ(tetrapage_get_contacts(object, &contact, 1, nullptr), invalid);
  EXPECT_EQ(tetrapage_get_contacts(object, nullptr, 0, &written), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_last_query_info(nullptr, &info), invalid);
  EXPECT_EQ(tetrapage_last_query_info(object, nullptr), invalid);
  // Releasing null does nothing.
  tetrapage_object_destroy(nullptr);
  tetrapage_close(nullptr);
  tetrapage_object_destroy(object);
}

TEST_F(CApiTest, BadObjectsAreInputOrFileErrors) {
  auto soup = small_object();
  auto vertices = flat_vertices(soup);
  auto triangles = flat_triangles(soup);
  tetrapage_object* object = nullptr;
  // An index out of range, named in the message.
  triangles[4] = std::uint32_t(soup.vertices.size());
  EXPECT_EQ(tetrapage_object_create(index_, vertices.data(), soup.vertices.size(), triangles.data(),
                                    soup.triangles.size(), &object),
            TETRAPAGE_ERROR_INPUT);
  EXPECT_NE(std::string(tetrapage_last_error()).find(std::to_string(soup.vertices.size())), std::string::npos)
      << tetrapage_last_error();
  triangles = flat_triangles(soup);
  // A NaN coordinate.
  vertices[7] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(tetrapage_object_create(index_, vertices.data(), soup.vertices.size(), triangles.data(),
                                    soup.triangles.size(), &object),
            TETRAPAGE_ERROR_INPUT);
  vertices = flat_vertices(soup);
  // No triangle.
  EXPECT_EQ(tetrapage_object_create(index_, vertices.data(), soup.vertices.size(), nullptr, 0, &object),
            TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(object, nullptr);

  const fs::path missing = folder_ / "no-such-object.obj";
  EXPECT_EQ(tetrapage_object_create_from_file(index_, missing.c_str(), &object), TETRAPAGE_ERROR_IO);
  EXPECT_NE(std::string(tetrapage_last_error()).find(missing.string()), std::string::npos)
      << tetrapage_last_error();
  const fs::path malformed = folder_ / "malformed.off";
  std::ofstream(malformed) << "OFF\n4 2 0\n0 0 0\n1 0 0\n";  // truncated vertex list
  EXPECT_EQ(tetrapage_object_create_from_file(index_, malformed.c_str(), &object), TETRAPAGE_ERROR_FORMAT)
      << tetrapage_last_error();
  EXPECT_EQ(object, nullptr);
}

TEST_F(CApiTest, InvalidPosesAndAccuraciesAreInputErrorsAndClearTheContacts) {
  tetrapage_object* object = create_object();
  ASSERT_NE(object, nullptr);
  // A colliding pose first, so that there are contacts to clear: the object straddles a face.
  const double touching[7] = {1.5, 0.75, 0.75, 1, 0, 0, 0};
  int collides = -1;
  ASSERT_EQ(tetrapage_query(object, touching, TETRAPAGE_ACCURACY_EXACT, 0, 1, &collides), TETRAPAGE_OK);
  ASSERT_EQ(collides, 1);
  std::size_t count = 0;
  ASSERT_EQ(tetrapage_contact_count(object, &count), TETRAPAGE_OK);
  ASSERT_GT(count, 0u);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const double bad_poses[][7] = {{nan, 0.75, 0.75, 1, 0, 0, 0},
                                 {0.75, 0.75, inf, 1, 0, 0, 0},
                                 {0.75, 0.75, 0.75, nan, 0, 0, 0},
                                 {0.75, 0.75, 0.75, 2, 0, 0, 0},
                                 {0.75, 0.75, 0.75, 0, 0, 0, 0}};
  for (const auto& pose : bad_poses) {
    collides = -1;
    EXPECT_EQ(tetrapage_query(object, pose, TETRAPAGE_ACCURACY_EXACT, 0, 1, &collides), TETRAPAGE_ERROR_INPUT);
    EXPECT_EQ(collides, 0);
    EXPECT_STRNE(tetrapage_last_error(), "");
    ASSERT_EQ(tetrapage_contact_count(object, &count), TETRAPAGE_OK);
    EXPECT_EQ(count, 0u);
  }
  EXPECT_EQ(tetrapage_query(object, touching, TETRAPAGE_ACCURACY_CLEARANCE, -1, 0, &collides), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_query(object, touching, TETRAPAGE_ACCURACY_CLEARANCE, nan, 0, &collides), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_query(object, touching, TETRAPAGE_ACCURACY_DOUBLE_EPS, nan, 0, &collides), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_query(object, touching, TETRAPAGE_ACCURACY_FLOAT_EPS, -1e-3, 0, &collides), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_query(object, touching, static_cast<tetrapage_accuracy>(42), 0, 0, &collides),
            TETRAPAGE_ERROR_INPUT);
  EXPECT_NE(std::string(tetrapage_last_error()).find("42"), std::string::npos) << tetrapage_last_error();
  // The object still works afterwards.
  EXPECT_EQ(tetrapage_query(object, touching, TETRAPAGE_ACCURACY_EXACT, 0, 0, &collides), TETRAPAGE_OK);
  EXPECT_EQ(collides, 1);
  tetrapage_object_destroy(object);
}

TEST_F(CApiTest, ShapedQueriesCollideWhereTheMeshDoesAndRejectUnknownShapes) {
  tetrapage_object* object = create_object();
  ASSERT_NE(object, nullptr);
  const double touching[7] = {1.5, 0.75, 0.75, 1, 0, 0, 0};
  int collides = -1;
  tetrapage_query_args args;
  for (const auto shape : {TETRAPAGE_SHAPE_MESH, TETRAPAGE_SHAPE_HULL, TETRAPAGE_SHAPE_BOX})
    for (const auto motion : {TETRAPAGE_MOTION_DISCRETE, TETRAPAGE_MOTION_SWEPT}) {
      tetrapage_query_args_init(&args);
      args.shape = shape;
      args.motion = motion;
      ASSERT_EQ(tetrapage_collide(object, touching, &args, &collides), TETRAPAGE_OK);
      EXPECT_EQ(collides, 1) << int(shape) << " " << int(motion);  // coarser shapes hold the object
      tetrapage_hit hit{};
      std::size_t written = 0;
      ASSERT_EQ(tetrapage_get_hits(object, &hit, 1, &written), TETRAPAGE_OK);
      ASSERT_EQ(written, 1u);
      // Solids name no object triangle (the second query of the loop sweeps).
      EXPECT_EQ(hit.object_triangle == TETRAPAGE_NO_OBJECT_TRIANGLE,
                shape != TETRAPAGE_SHAPE_MESH || motion == TETRAPAGE_MOTION_SWEPT);
      EXPECT_NE(hit.environment_component, TETRAPAGE_NO_COMPONENT);
      EXPECT_EQ(hit.dynamic_part, 0u);
    }
  tetrapage_query_args_init(&args);
  args.shape = 7;
  EXPECT_EQ(tetrapage_collide(object, touching, &args, &collides), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(collides, 0);
  tetrapage_query_args_init(&args);
  args.motion = 9;
  EXPECT_EQ(tetrapage_collide(object, touching, &args, &collides), TETRAPAGE_ERROR_INPUT);
  EXPECT_NE(std::string(tetrapage_last_error()).find("9"), std::string::npos) << tetrapage_last_error();
  tetrapage_object_destroy(object);
}

TEST_F(CApiTest, ParseAccuracyFollowsTheCommandLineSyntax) {
  tetrapage_accuracy accuracy = TETRAPAGE_ACCURACY_EXACT;
  double parameter = -1;
  ASSERT_EQ(tetrapage_parse_accuracy("clearance:0.25", &accuracy, &parameter), TETRAPAGE_OK);
  EXPECT_EQ(accuracy, TETRAPAGE_ACCURACY_CLEARANCE);
  EXPECT_EQ(parameter, 0.25);
  ASSERT_EQ(tetrapage_parse_accuracy("float_eps:1e-4", &accuracy, &parameter), TETRAPAGE_OK);
  EXPECT_EQ(accuracy, TETRAPAGE_ACCURACY_FLOAT_EPS);
  EXPECT_EQ(parameter, 1e-4);
  ASSERT_EQ(tetrapage_parse_accuracy("double_eps", &accuracy, &parameter), TETRAPAGE_OK);
  EXPECT_EQ(accuracy, TETRAPAGE_ACCURACY_DOUBLE_EPS);
  EXPECT_EQ(parameter, 0.0);
  ASSERT_EQ(tetrapage_parse_accuracy("exact", &accuracy, &parameter), TETRAPAGE_OK);
  EXPECT_EQ(accuracy, TETRAPAGE_ACCURACY_EXACT);
  EXPECT_EQ(tetrapage_parse_accuracy("roughly", &accuracy, &parameter), TETRAPAGE_ERROR_INPUT);
  EXPECT_NE(std::string(tetrapage_last_error()).find("roughly"), std::string::npos) << tetrapage_last_error();
  EXPECT_EQ(tetrapage_parse_accuracy("clearance:-1", &accuracy, &parameter), TETRAPAGE_ERROR_INPUT);
}

TEST_F(CApiTest, BoundsAreTheModelsBox) {
  double lo[3], hi[3];
  ASSERT_EQ(tetrapage_index_bounds(index_, lo, hi), TETRAPAGE_OK);
  const BoundingBox expected = environment_.bounds();
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(lo[a], expected.lo[a]);
    EXPECT_EQ(hi[a], expected.hi[a]);
  }
}

// Parts by name and path, the model's unit, and stored triangles by id, as the soup read back
// holds them; strings are cut to fit and always terminated.
TEST_F(CApiTest, PartsUnitAndTrianglesByIdAreTheModels) {
  std::uint32_t parts = 0;
  ASSERT_EQ(tetrapage_index_part_count(index_, &parts), TETRAPAGE_OK);
  ASSERT_EQ(parts, environment_.part_count());
  char text[256];
  std::size_t length = 0;
  for (std::uint32_t p = 0; p < parts; ++p) {
    ASSERT_EQ(tetrapage_index_part_name(index_, p, text, sizeof text, &length), TETRAPAGE_OK);
    EXPECT_EQ(std::string(text), environment_.part_names[p]);
    EXPECT_EQ(length, environment_.part_names[p].size());
    ASSERT_EQ(tetrapage_index_part_path(index_, p, text, sizeof text, &length), TETRAPAGE_OK);
    EXPECT_EQ(std::string(text), environment_.part_path(p));
  }
  const std::string name = environment_.part_names[0];
  ASSERT_GT(name.size(), 3u);
  char small[4] = {'x', 'x', 'x', 'x'};
  ASSERT_EQ(tetrapage_index_part_name(index_, 0, small, sizeof small, &length), TETRAPAGE_OK);
  EXPECT_EQ(std::string(small), name.substr(0, 3));
  EXPECT_EQ(length, name.size());
  EXPECT_EQ(tetrapage_index_part_name(index_, 0, nullptr, 0, &length), TETRAPAGE_OK);
  EXPECT_EQ(length, name.size());
  EXPECT_EQ(tetrapage_index_part_name(index_, 0, text, sizeof text, nullptr), TETRAPAGE_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(tetrapage_index_part_name(index_, parts, text, sizeof text, &length), TETRAPAGE_ERROR_INPUT);
  EXPECT_NE(std::string(tetrapage_last_error()).find("no part"), std::string::npos) << tetrapage_last_error();
  ASSERT_EQ(tetrapage_index_length_unit(index_, text, sizeof text, &length), TETRAPAGE_OK);
  EXPECT_EQ(std::string(text), "");  // a plain mesh preprocessed without --unit

  double corners[9];
  std::uint32_t part = 0;
  for (std::uint64_t id = 0; id < environment_.triangle_count(); ++id) {
    ASSERT_EQ(tetrapage_index_triangle(index_, id, corners, &part), TETRAPAGE_OK) << tetrapage_last_error();
    const auto expected = environment_.corners(id);
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) EXPECT_EQ(corners[3 * k + a], expected[k][a]) << id;
    EXPECT_EQ(part, environment_.part_of[id]);
  }
  EXPECT_EQ(tetrapage_index_triangle(index_, environment_.triangle_count(), corners, &part), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_index_triangle(index_, 0, nullptr, &part), TETRAPAGE_ERROR_INVALID_ARGUMENT);
}

// The answers of the C API are the C++ API's, and both are the brute force's, on random poses,
// for the exact mode (first hit and all contacts) and a clearance.
TEST_F(CApiTest, AnswersEqualTheCppApiAndBruteForce) {
  constexpr std::uint64_t kSeed = 20240605;
  SCOPED_TRACE("seed " + std::to_string(kSeed));
  Uniform uniform(kSeed);
  tetrapage_object* object = create_object();
  ASSERT_NE(object, nullptr);
  auto shared = std::make_shared<const CollisionIndex>(index_path_, CollisionIndexOptions{kBudget, true, 1});
  FlyingObject reference(shared, small_object());

  struct Setting {
    tetrapage_accuracy accuracy;
    double parameter;
    geometry::Accuracy cpp;
  };
  const Setting settings[] = {{TETRAPAGE_ACCURACY_EXACT, 0, geometry::Accuracy::exact()},
                              {TETRAPAGE_ACCURACY_CLEARANCE, 0.05, geometry::Accuracy::within(0.05)}};
  std::size_t collisions = 0, poses = 0;
  for (int k = 0; k < 150; ++k) {
    const auto p = random_pose(uniform);
    for (const auto& setting : settings) {
      SCOPED_TRACE("pose " + std::to_string(k) + ", accuracy " + geometry::to_string(setting.cpp));
      const auto expected = brute_force(p, setting.cpp);
      for (const int all : {0, 1}) {
        // The deprecated call answers as the call that replaces it (compared below).
        int deprecated_collides = -1;
        ASSERT_EQ(tetrapage_query(object, p.data(), setting.accuracy, setting.parameter, all,
                                  &deprecated_collides),
                  TETRAPAGE_OK);
        std::size_t deprecated_count = 0, deprecated_written = 0;
        ASSERT_EQ(tetrapage_contact_count(object, &deprecated_count), TETRAPAGE_OK);
        std::vector<tetrapage_contact> deprecated(deprecated_count);
        ASSERT_EQ(tetrapage_get_contacts(object, deprecated.data(), deprecated.size(),
                                         &deprecated_written),
                  TETRAPAGE_OK);
        tetrapage_query_args args;
        tetrapage_query_args_init(&args);
        args.accuracy = setting.accuracy;
        args.parameter = setting.parameter;
        args.contacts = all ? TETRAPAGE_CONTACTS_ALL : TETRAPAGE_CONTACTS_FIRST;
        int collides = -1;
        ASSERT_EQ(tetrapage_collide(object, p.data(), &args, &collides), TETRAPAGE_OK)
            << tetrapage_last_error();
        EXPECT_EQ(deprecated_collides, collides);
        const QueryResult cpp = reference.query(
            to_pose(p), QueryOptions{setting.cpp, all ? QueryMode::all_contacts : QueryMode::first_hit});
        EXPECT_EQ(collides, cpp.collides ? 1 : 0);
        EXPECT_EQ(collides, expected.empty() ? 0 : 1);

        std::size_t count = 0, written = 0;
        ASSERT_EQ(tetrapage_contact_count(object, &count), TETRAPAGE_OK);
        std::vector<tetrapage_hit> contacts(count + 1);
        ASSERT_EQ(tetrapage_get_hits(object, contacts.data(), contacts.size(), &written),
                  TETRAPAGE_OK);
        ASSERT_EQ(written, count);
        contacts.resize(written);
        EXPECT_EQ(contact_set(contacts), contact_set(cpp.contacts));
        EXPECT_EQ(contact_set(deprecated), contact_set(contacts));
        if (all) {
          EXPECT_EQ(contact_set(contacts), expected);
        } else {
          EXPECT_EQ(count, collides ? 1u : 0u);
          if (count == 1) {
            EXPECT_EQ(expected.count(*contact_set(contacts).begin()), 1u);
          }
        }

        tetrapage_query_info info;
        ASSERT_EQ(tetrapage_last_query_info(object, &info), TETRAPAGE_OK);
        EXPECT_EQ(info.collides, collides);
        EXPECT_EQ(info.outside_model, cpp.outside_model ? 1 : 0);
        EXPECT_EQ(info.triangle_tests, cpp.counters.triangle_tests);
        EXPECT_EQ(info.candidates, cpp.counters.candidates);
        // The reported box holds the placed object.
        const TriangleSoup soup = small_object();
        for (const auto& v : soup.vertices) {
          const Vec3 w = apply_pose(to_pose(p), v);
          for (int a = 0; a < 3; ++a) {
            EXPECT_LE(info.world_lo[a], w[a]);
            EXPECT_GE(info.world_hi[a], w[a]);
          }
        }
        if (setting.accuracy == TETRAPAGE_ACCURACY_EXACT && all) {
          collisions += std::size_t(collides);
          ++poses;
        }
      }
    }
  }
  // Both answers occur, so the comparison means something.
  EXPECT_GT(collisions, 10u);
  EXPECT_LT(collisions, poses - 10);
  tetrapage_object_destroy(object);
}

TEST_F(CApiTest, DistanceImpactAndContactGeometryEqualTheCppApi) {
  Uniform uniform(27);
  tetrapage_object* object = create_object();
  ASSERT_NE(object, nullptr);
  auto shared = std::make_shared<const CollisionIndex>(index_path_, CollisionIndexOptions{kBudget, true, 1});
  FlyingObject reference(shared, small_object());
  int touching = 0, apart = 0, geometries = 0;
  std::array<double, 7> previous = random_pose(uniform);
  for (int k = 0; k < 150; ++k) {
    const auto p = random_pose(uniform);
    SCOPED_TRACE("pose " + std::to_string(k));
    tetrapage_distance deprecated_distance;
    ASSERT_EQ(tetrapage_distance_query(object, p.data(), INFINITY, &deprecated_distance),
              TETRAPAGE_OK);
    tetrapage_distance_result distance;
    ASSERT_EQ(tetrapage_measure_distance(object, p.data(), nullptr, &distance), TETRAPAGE_OK)
        << tetrapage_last_error();
    EXPECT_EQ(deprecated_distance.distance, distance.distance);
    EXPECT_EQ(deprecated_distance.environment_triangle, distance.closest.environment_triangle);
    const DistanceResult cpp = reference.distance(to_pose(p));
    EXPECT_EQ(distance.separation, int(cpp.separation));
    EXPECT_EQ(distance.distance, cpp.distance);
    EXPECT_EQ(distance.lower_bound, cpp.lower_bound);
    EXPECT_EQ(distance.upper_bound, cpp.upper_bound);
    EXPECT_EQ(distance.closest.environment_triangle, cpp.closest.environment_triangle);
    EXPECT_EQ(distance.closest.environment_component, TETRAPAGE_NO_COMPONENT);
    if (!cpp.closest.has_triangle()) {
      EXPECT_EQ(distance.closest.object_triangle, TETRAPAGE_NO_OBJECT_TRIANGLE);
    } else {
      EXPECT_EQ(distance.closest.object_triangle, cpp.closest.object_triangle);
      EXPECT_EQ(distance.closest.environment_part, cpp.closest.environment_part);
    }
    for (int a = 0; a < 3; ++a) EXPECT_EQ(distance.on_object[a], cpp.on_object[a]);
    touching += distance.separation == 0;
    apart += distance.separation == 1;
    // Touching is what the collision query says; its contacts' geometry is the C++ API's.
    int collides = -1;
    tetrapage_query_args all;
    tetrapage_query_args_init(&all);
    all.contacts = TETRAPAGE_CONTACTS_ALL;
    ASSERT_EQ(tetrapage_collide(object, p.data(), &all, &collides), TETRAPAGE_OK);
    EXPECT_EQ(collides, distance.separation == 0 ? 1 : 0);
    const QueryResult contacts = reference.query(to_pose(p), QueryOptions{{}, QueryMode::all_contacts});
    std::size_t count = 0;
    ASSERT_EQ(tetrapage_contact_count(object, &count), TETRAPAGE_OK);
    std::vector<tetrapage_hit> listed(count);
    std::size_t written = 0;
    ASSERT_EQ(tetrapage_get_hits(object, listed.data(), count, &written), TETRAPAGE_OK);
    for (std::size_t c = 0; c < written; ++c) {
      tetrapage_contact_geometry geometry;
      ASSERT_EQ(tetrapage_get_contact_geometry(object, c, &geometry), TETRAPAGE_OK) << tetrapage_last_error();
      const Contact same{listed[c].environment_part, listed[c].environment_triangle, listed[c].object_triangle,
                         listed[c].environment_component};
      const geometry::ContactGeometry expected = reference.contact_geometry(same);
      EXPECT_EQ(geometry.shape, int(expected.shape));
      EXPECT_NE(geometry.shape, 0);
      ASSERT_EQ(geometry.point_count, expected.count);
      for (std::uint32_t i = 0; i < geometry.point_count; ++i)
        for (int a = 0; a < 3; ++a) EXPECT_EQ(geometry.points[i][a], expected.points[i][a]);
      ++geometries;
    }
    tetrapage_contact_geometry none;
    EXPECT_EQ(tetrapage_get_contact_geometry(object, written, &none), TETRAPAGE_ERROR_INPUT);
    // The motion from the previous pose: the C++ API's answer.
    tetrapage_impact deprecated_impact;
    ASSERT_EQ(tetrapage_time_of_impact(object, previous.data(), p.data(), 1e-3, &deprecated_impact),
              TETRAPAGE_OK);
    tetrapage_impact_args impact_args;
    tetrapage_impact_args_init(&impact_args);
    impact_args.tolerance = 1e-3;
    tetrapage_impact_result impact;
    ASSERT_EQ(tetrapage_find_impact(object, previous.data(), p.data(), &impact_args, &impact),
              TETRAPAGE_OK)
        << tetrapage_last_error();
    EXPECT_EQ(deprecated_impact.contact_at, impact.contact_at);
    ImpactOptions options;
    options.tolerance = 1e-3;
    const ImpactResult expected = reference.time_of_impact(to_pose(previous), to_pose(p), options);
    EXPECT_EQ(impact.impact, int(expected.impact));
    EXPECT_EQ(impact.free_until, expected.free_until);
    EXPECT_EQ(impact.contact_at, expected.contact_at);
    if (expected.contact.has_triangle()) {
      EXPECT_EQ(impact.first_contact.environment_triangle, expected.contact.environment_triangle);
      EXPECT_EQ(impact.first_contact.object_triangle, expected.contact.object_triangle);
      EXPECT_EQ(deprecated_impact.environment_triangle, expected.contact.environment_triangle);
    } else {
      EXPECT_EQ(impact.first_contact.environment_triangle, TETRAPAGE_NO_TRIANGLE);
      EXPECT_EQ(impact.first_contact.object_triangle, TETRAPAGE_NO_OBJECT_TRIANGLE);
    }
    EXPECT_EQ(impact.containment, int(expected.containment));
    previous = p;
  }
  EXPECT_GT(touching, 3);
  EXPECT_GT(apart, 5);
  EXPECT_GT(geometries, 3);
  tetrapage_distance distance;
  tetrapage_impact impact;
  const double pose[7] = {0, 0, 0, 1, 0, 0, 0};
  EXPECT_EQ(tetrapage_distance_query(object, pose, -1.0, &distance), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_distance_query(object, pose, NAN, &distance), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_distance_query(object, nullptr, 1.0, &distance), TETRAPAGE_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(tetrapage_distance_query(object, pose, 1.0, nullptr), TETRAPAGE_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(tetrapage_time_of_impact(object, pose, pose, 0.0, &impact), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_time_of_impact(object, pose, pose, 2.0, &impact), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_time_of_impact(object, pose, nullptr, 0.1, &impact), TETRAPAGE_ERROR_INVALID_ARGUMENT);
  tetrapage_object_destroy(object);
}

// The growth rule of tetrapage.h: a struct_size that ends before a field (a caller compiled
// against an older header) reads that field's default, however its bytes are set.
TEST_F(CApiTest, ArgumentStructsReadTheFieldsTheirSizeCoversAndDefaultTheRest) {
  tetrapage_object* object = create_object();
  ASSERT_NE(object, nullptr);
  const double pose[7] = {1.5, 1.5, 0.75, std::cos(0.3), 0.2, 0, std::sin(0.3)};
  const double norm = std::sqrt(pose[3] * pose[3] + pose[4] * pose[4] + pose[6] * pose[6]);
  const double unit[7] = {pose[0],        pose[1], pose[2],       pose[3] / norm,
                          pose[4] / norm, 0,       pose[6] / norm};
  int collides = -1;
  std::size_t count = 0;

  // Null: every default (the first contact only).
  ASSERT_EQ(tetrapage_collide(object, unit, nullptr, &collides), TETRAPAGE_OK)
      << tetrapage_last_error();
  ASSERT_EQ(tetrapage_contact_count(object, &count), TETRAPAGE_OK);
  EXPECT_EQ(collides, 1);
  EXPECT_EQ(count, 1u);

  tetrapage_query_args args;
  tetrapage_query_args_init(&args);
  EXPECT_EQ(args.struct_size, sizeof args);
  args.contacts = TETRAPAGE_CONTACTS_ALL;
  ASSERT_EQ(tetrapage_collide(object, unit, &args, &collides), TETRAPAGE_OK);
  ASSERT_EQ(tetrapage_contact_count(object, &count), TETRAPAGE_OK);
  const std::size_t all_contacts = count;
  ASSERT_GT(all_contacts, 1u);

  // max_contacts read: more contacts than it allows is an error naming the limit.
  args.max_contacts = 1;
  EXPECT_EQ(tetrapage_collide(object, unit, &args, &collides), TETRAPAGE_ERROR_INPUT);
  EXPECT_NE(std::string(tetrapage_last_error()).find("more than 1 contacts"), std::string::npos)
      << tetrapage_last_error();
  // A struct that ends before max_contacts: the default limit, not the bytes past its size.
  args.struct_size = offsetof(tetrapage_query_args, max_contacts);
  ASSERT_EQ(tetrapage_collide(object, unit, &args, &collides), TETRAPAGE_OK)
      << tetrapage_last_error();
  ASSERT_EQ(tetrapage_contact_count(object, &count), TETRAPAGE_OK);
  EXPECT_EQ(count, all_contacts);
  // One that ends before contacts: the first contact only.
  args.struct_size = offsetof(tetrapage_query_args, contacts);
  ASSERT_EQ(tetrapage_collide(object, unit, &args, &collides), TETRAPAGE_OK);
  ASSERT_EQ(tetrapage_contact_count(object, &count), TETRAPAGE_OK);
  EXPECT_EQ(count, 1u);

  // Sizes this library cannot read, and values outside the enumerations.
  for (const std::size_t size : {std::size_t(0), sizeof(std::size_t) - 1, sizeof args + 8}) {
    args.struct_size = size;
    EXPECT_EQ(tetrapage_collide(object, unit, &args, &collides), TETRAPAGE_ERROR_INVALID_ARGUMENT)
        << size;
    EXPECT_NE(std::string(tetrapage_last_error()).find("struct_size is " + std::to_string(size)),
              std::string::npos)
        << tetrapage_last_error();
    EXPECT_EQ(collides, 0);
  }
  tetrapage_query_args_init(&args);
  args.contacts = 2;
  EXPECT_EQ(tetrapage_collide(object, unit, &args, &collides), TETRAPAGE_ERROR_INPUT);
  tetrapage_query_args_init(&args);
  args.max_contacts = 0;
  EXPECT_EQ(tetrapage_collide(object, unit, &args, &collides), TETRAPAGE_ERROR_INPUT);
  tetrapage_query_args_init(&args);
  args.accuracy = 42;
  EXPECT_EQ(tetrapage_collide(object, unit, &args, &collides), TETRAPAGE_ERROR_INPUT);
  tetrapage_query_args_init(nullptr);  // ignored

  // Distance: max_distance read, or its default (any distance) past the struct's size.
  const double far[7] = {40, 40, 40, 1, 0, 0, 0};
  tetrapage_distance_args near;
  tetrapage_distance_args_init(&near);
  near.max_distance = 1;
  tetrapage_distance_result distance;
  ASSERT_EQ(tetrapage_measure_distance(object, far, &near, &distance), TETRAPAGE_OK)
      << tetrapage_last_error();
  EXPECT_EQ(distance.separation, 2);  // farther: not measured
  EXPECT_EQ(distance.closest.environment_triangle, TETRAPAGE_NO_TRIANGLE);
  EXPECT_EQ(distance.closest.object_triangle, TETRAPAGE_NO_OBJECT_TRIANGLE);
  near.struct_size = offsetof(tetrapage_distance_args, max_distance);
  ASSERT_EQ(tetrapage_measure_distance(object, far, &near, &distance), TETRAPAGE_OK);
  EXPECT_EQ(distance.separation, 1);
  EXPECT_NE(distance.closest.environment_triangle, TETRAPAGE_NO_TRIANGLE);
  near.struct_size = 1;
  EXPECT_EQ(tetrapage_measure_distance(object, far, &near, &distance),
            TETRAPAGE_ERROR_INVALID_ARGUMENT);
  tetrapage_distance_args_init(&near);
  near.max_distance = -1;
  EXPECT_EQ(tetrapage_measure_distance(object, far, &near, &distance), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_measure_distance(object, far, nullptr, nullptr),
            TETRAPAGE_ERROR_INVALID_ARGUMENT);

  // Time of impact: one iteration leaves a long motion unresolved; the default limit resolves it.
  const double from[7] = {-6, 0.75, 0.75, 1, 0, 0, 0};
  tetrapage_impact_args impact_args;
  tetrapage_impact_args_init(&impact_args);
  EXPECT_EQ(impact_args.max_iterations, 10000u);
  impact_args.max_iterations = 1;
  tetrapage_impact_result impact;
  ASSERT_EQ(tetrapage_find_impact(object, from, unit, &impact_args, &impact), TETRAPAGE_OK)
      << tetrapage_last_error();
  EXPECT_EQ(impact.impact, 2);
  EXPECT_LE(impact.iterations, 1u);
  impact_args.struct_size = offsetof(tetrapage_impact_args, max_iterations);
  ASSERT_EQ(tetrapage_find_impact(object, from, unit, &impact_args, &impact), TETRAPAGE_OK);
  EXPECT_EQ(impact.impact, 1);
  EXPECT_NE(impact.first_contact.environment_triangle, TETRAPAGE_NO_TRIANGLE);
  tetrapage_impact_args_init(&impact_args);
  impact_args.max_iterations = 0;
  EXPECT_EQ(tetrapage_find_impact(object, from, unit, &impact_args, &impact),
            TETRAPAGE_ERROR_INPUT);
  impact_args.max_iterations = std::uint64_t(1) << 32;
  EXPECT_EQ(tetrapage_find_impact(object, from, unit, &impact_args, &impact),
            TETRAPAGE_ERROR_INPUT);
  tetrapage_impact_args_init(&impact_args);
  impact_args.tolerance = 0;
  EXPECT_EQ(tetrapage_find_impact(object, from, unit, &impact_args, &impact),
            TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_find_impact(object, from, nullptr, nullptr, &impact),
            TETRAPAGE_ERROR_INVALID_ARGUMENT);
  tetrapage_object_destroy(object);
}

TEST_F(CApiTest, ContactsCopyAPrefixWhenTheBufferIsSmall) {
  tetrapage_object* object = create_object();
  ASSERT_NE(object, nullptr);
  // Across an edge of the first box: many contacts.
  const double pose[7] = {1.5, 1.5, 0.75, std::cos(0.3), 0.2, 0, std::sin(0.3)};
  const double norm = std::sqrt(pose[3] * pose[3] + pose[4] * pose[4] + pose[6] * pose[6]);
  const double unit[7] = {pose[0], pose[1], pose[2], pose[3] / norm, pose[4] / norm, 0, pose[6] / norm};
  int collides = 0;
  ASSERT_EQ(tetrapage_query(object, unit, TETRAPAGE_ACCURACY_EXACT, 0, 1, &collides), TETRAPAGE_OK);
  std::size_t count = 0, written = 0;
  ASSERT_EQ(tetrapage_contact_count(object, &count), TETRAPAGE_OK);
  ASSERT_GT(count, 3u);
  std::vector<tetrapage_contact> all(count), some(2);
  ASSERT_EQ(tetrapage_get_contacts(object, all.data(), all.size(), &written), TETRAPAGE_OK);
  ASSERT_EQ(written, count);
  ASSERT_EQ(tetrapage_get_contacts(object, some.data(), some.size(), &written), TETRAPAGE_OK);
  ASSERT_EQ(written, 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(some[i].environment_triangle, all[i].environment_triangle);
    EXPECT_EQ(some[i].environment_part, all[i].environment_part);
    EXPECT_EQ(some[i].object_triangle, all[i].object_triangle);
  }
  tetrapage_object_destroy(object);
}

TEST_F(CApiTest, ObjectsFromFilesAnswerAsObjectsFromArraysAndOutliveTheirIndex) {
  tetrapage_object* from_arrays = create_object();
  tetrapage_object* from_file = nullptr;
  ASSERT_EQ(tetrapage_object_create_from_file(index_, (folder_ / "object.obj").c_str(), &from_file), TETRAPAGE_OK)
      << tetrapage_last_error();
  // Closing the index handle leaves the objects working; the handle itself is stale.
  ASSERT_EQ(tetrapage_close(index_), TETRAPAGE_OK);
  double lo[3], hi[3];
  EXPECT_EQ(tetrapage_index_bounds(index_, lo, hi), TETRAPAGE_ERROR_STALE_HANDLE);
  tetrapage_object* late = nullptr;
  EXPECT_EQ(tetrapage_object_create_from_file(index_, (folder_ / "object.obj").c_str(), &late),
            TETRAPAGE_ERROR_STALE_HANDLE);
  EXPECT_EQ(late, nullptr);
  index_ = nullptr;
  Uniform uniform(7);
  for (int k = 0; k < 40; ++k) {
    const auto p = random_pose(uniform);
    int a = -1, b = -1;
    ASSERT_EQ(tetrapage_query(from_arrays, p.data(), TETRAPAGE_ACCURACY_EXACT, 0, 1, &a), TETRAPAGE_OK);
    ASSERT_EQ(tetrapage_query(from_file, p.data(), TETRAPAGE_ACCURACY_EXACT, 0, 1, &b), TETRAPAGE_OK);
    EXPECT_EQ(a, b) << "pose " << k << " (seed 7)";
    EXPECT_EQ(a, brute_force(p, geometry::Accuracy::exact()).empty() ? 0 : 1) << "pose " << k << " (seed 7)";
  }
  EXPECT_EQ(tetrapage_object_destroy(from_arrays), TETRAPAGE_OK);
  // The last object frees the index; the other keeps answering until then.
  int collides = -1;
  const double pose[7] = {1.5, 0.75, 0.75, 1, 0, 0, 0};
  EXPECT_EQ(tetrapage_query(from_file, pose, TETRAPAGE_ACCURACY_EXACT, 0, 0, &collides), TETRAPAGE_OK);
  EXPECT_EQ(collides, 1);
  EXPECT_EQ(tetrapage_object_destroy(from_file), TETRAPAGE_OK);
}

TEST_F(CApiTest, NoQueryMeansNoContacts) {
  tetrapage_object* object = create_object();
  ASSERT_NE(object, nullptr);
  std::size_t count = 1;
  ASSERT_EQ(tetrapage_contact_count(object, &count), TETRAPAGE_OK);
  EXPECT_EQ(count, 0u);
  tetrapage_query_info info;
  info.collides = 7;
  ASSERT_EQ(tetrapage_last_query_info(object, &info), TETRAPAGE_OK);
  EXPECT_EQ(info.collides, 0);
  EXPECT_EQ(info.triangle_tests, 0u);
  tetrapage_object_destroy(object);
}

// Closing or destroying twice, and any use of a released handle, is a status, never a crash:
// handles are ids looked up in a table, not pointers to freed memory.
TEST_F(CApiTest, StaleHandlesAreReportedNeverDereferenced) {
  constexpr auto stale = TETRAPAGE_ERROR_STALE_HANDLE;
  const auto names = [](const char* word) {
    return std::string(tetrapage_last_error()).find(word) != std::string::npos;
  };
  tetrapage_index* index = nullptr;
  ASSERT_EQ(tetrapage_open(index_path_.c_str(), kBudget, &index), TETRAPAGE_OK);
  tetrapage_object* object = nullptr;
  ASSERT_EQ(tetrapage_object_create_from_file(index, (folder_ / "object.obj").c_str(), &object), TETRAPAGE_OK);
  ASSERT_EQ(tetrapage_close(index), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_close(index), stale);
  EXPECT_TRUE(names("tetrapage_close") && names("index handle") && names("stale")) << tetrapage_last_error();
  double lo[3], hi[3];
  EXPECT_EQ(tetrapage_index_bounds(index, lo, hi), stale);

  const double pose[7] = {0.75, 0.75, 0.75, 1, 0, 0, 0};
  int collides = -1;
  ASSERT_EQ(tetrapage_query(object, pose, TETRAPAGE_ACCURACY_EXACT, 0, 1, &collides), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_object_destroy(object), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_object_destroy(object), stale);
  EXPECT_TRUE(names("object handle")) << tetrapage_last_error();
  EXPECT_EQ(tetrapage_query(object, pose, TETRAPAGE_ACCURACY_EXACT, 0, 1, &collides), stale);
  EXPECT_EQ(collides, 0);
  EXPECT_EQ(tetrapage_collide(object, pose, nullptr, &collides), stale);
  std::size_t count = 7, written = 7;
  tetrapage_contact contact;
  tetrapage_query_info info;
  EXPECT_EQ(tetrapage_contact_count(object, &count), stale);
  EXPECT_EQ(count, 0u);
  EXPECT_EQ(tetrapage_get_contacts(object, &contact, 1, &written), stale);
  EXPECT_EQ(written, 0u);
  tetrapage_hit hit;
  written = 7;
  EXPECT_EQ(tetrapage_get_hits(object, &hit, 1, &written), stale);
  EXPECT_EQ(written, 0u);
  EXPECT_EQ(tetrapage_last_query_info(object, &info), stale);

  // A handle of the other kind, and one this library never returned, are stale too.
  tetrapage_object* live = create_object();
  ASSERT_NE(live, nullptr);
  EXPECT_EQ(tetrapage_close(reinterpret_cast<tetrapage_index*>(live)), stale);
  EXPECT_EQ(tetrapage_object_destroy(reinterpret_cast<tetrapage_object*>(index_)), stale);
  int local = 0;
  EXPECT_EQ(tetrapage_object_destroy(reinterpret_cast<tetrapage_object*>(&local)), stale);
  EXPECT_EQ(tetrapage_query(live, pose, TETRAPAGE_ACCURACY_EXACT, 0, 0, &collides), TETRAPAGE_OK)
      << "a failed release must not touch live handles";
  EXPECT_EQ(tetrapage_object_destroy(live), TETRAPAGE_OK);
  // Null stays a no-op, and a success clears the message.
  EXPECT_EQ(tetrapage_close(nullptr), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_object_destroy(nullptr), TETRAPAGE_OK);
  EXPECT_STREQ(tetrapage_last_error(), "");
}

// Threads creating, querying and releasing handles at once while others release theirs twice:
// the table stays consistent (run under the sanitizers by the threads build too).
TEST_F(CApiTest, HandlesAreReleasedSafelyFromManyThreads) {
  std::vector<std::thread> threads;
  std::vector<int> failures(4, 0);
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      const double pose[7] = {0.75 + 0.1 * t, 0.75, 0.75, 1, 0, 0, 0};
      for (int round = 0; round < 20; ++round) {
        tetrapage_object* object = create_object();
        int collides = -1;
        if (tetrapage_query(object, pose, TETRAPAGE_ACCURACY_EXACT, 0, 0, &collides) != TETRAPAGE_OK) ++failures[t];
        if (tetrapage_object_destroy(object) != TETRAPAGE_OK) ++failures[t];
        if (tetrapage_object_destroy(object) != TETRAPAGE_ERROR_STALE_HANDLE) ++failures[t];
      }
    });
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(failures, std::vector<int>(4, 0));
}

// Objects that could only fail later (no area, coordinates whose placement overflows), poses
// that overflow, and budgets smaller than a shard are input errors where they are given.
TEST_F(CApiTest, BadObjectsPosesAndBudgetsAreInputErrorsUpFront) {
  tetrapage_object* object = nullptr;
  const double collinear[] = {0, 0, 0, 0.1, 0.1, 0.1, 0.2, 0.2, 0.2};
  const std::uint32_t triangles[] = {0, 1, 2, 2, 2, 0};
  EXPECT_EQ(tetrapage_object_create(index_, collinear, 3, triangles, 2, &object), TETRAPAGE_ERROR_INPUT);
  EXPECT_NE(std::string(tetrapage_last_error()).find("zero area"), std::string::npos) << tetrapage_last_error();
  EXPECT_EQ(object, nullptr);
  const auto soup = small_object();
  auto vertices = flat_vertices(soup);
  const auto indices = flat_triangles(soup);
  vertices[4] = 1e308;
  EXPECT_EQ(tetrapage_object_create(index_, vertices.data(), soup.vertices.size(), indices.data(),
                                    soup.triangles.size(), &object),
            TETRAPAGE_ERROR_INPUT);
  EXPECT_NE(std::string(tetrapage_last_error()).find("1e+308"), std::string::npos) << tetrapage_last_error();
  EXPECT_EQ(object, nullptr);

  object = create_object();
  ASSERT_NE(object, nullptr);
  const double overflowing[7] = {1e308, 1e308, 1e308, 1, 0, 0, 0};
  int collides = -1;
  EXPECT_EQ(tetrapage_query(object, overflowing, TETRAPAGE_ACCURACY_EXACT, 0, 0, &collides), TETRAPAGE_ERROR_INPUT);
  EXPECT_NE(std::string(tetrapage_last_error()).find("overflow"), std::string::npos) << tetrapage_last_error();
  EXPECT_EQ(tetrapage_object_destroy(object), TETRAPAGE_OK);

  const CollisionIndex probe(index_path_);
  std::uint64_t largest = 0;
  for (std::uint32_t s = 0; s < probe.shard_count(); ++s) largest = std::max(largest, probe.shard_bytes(s));
  tetrapage_index* index = nullptr;
  EXPECT_EQ(tetrapage_open(index_path_.c_str(), largest - 1, &index), TETRAPAGE_ERROR_INPUT);
  EXPECT_NE(std::string(tetrapage_last_error()).find(std::to_string(largest - 1)), std::string::npos)
      << tetrapage_last_error();
  EXPECT_EQ(index, nullptr);
  ASSERT_EQ(tetrapage_open(index_path_.c_str(), largest, &index), TETRAPAGE_OK) << tetrapage_last_error();
  EXPECT_EQ(tetrapage_close(index), TETRAPAGE_OK);
}

// A copy whose shards away from the first box are overwritten on disk after it was opened (with
// the prefetcher on): queries there fail naming the file and a shard, queries by the first box
// keep answering, and the object that failed answers again elsewhere.
TEST_F(CApiTest, ShardsDamagedAfterOpeningFailOnlyTheirQueries) {
  const fs::path copy = folder_ / "damaged-later.tpi";
  fs::copy_file(index_path_, copy, fs::copy_options::overwrite_existing);
  tetrapage_index* index = nullptr;
  ASSERT_EQ(tetrapage_open(copy.c_str(), kBudget, &index), TETRAPAGE_OK);
  tetrapage_object* near_first = nullptr;
  tetrapage_object* near_second = nullptr;
  const auto object = small_object();
  const auto vertices = flat_vertices(object);
  const auto triangles = flat_triangles(object);
  for (auto* created : {&near_first, &near_second})
    ASSERT_EQ(tetrapage_object_create(index, vertices.data(), object.vertices.size(), triangles.data(),
                                      object.triangles.size(), created),
              TETRAPAGE_OK);
  {
    // Every shard holding no triangle of the first box: garbage over their stored chunks.
    const CollisionIndex probe(copy);
    const IndexReader reader(copy);
    std::fstream file(copy, std::ios::in | std::ios::out | std::ios::binary);
    for (std::uint32_t s = 0; s < probe.shard_count(); ++s) {
      const auto& b = probe.shard_bounds(s);
      if (b.lo[0] <= 1.6 && b.lo[1] <= 1.6 && b.lo[2] <= 1.6) continue;  // it meets the first
      for (const StoredChunk& chunk : reader.shard_chunks(s)) {
        const std::string garbage(chunk.stored_bytes / 2 + 1, '\x5a');
        file.seekp(std::streamoff(chunk.file_offset + chunk.stored_bytes / 4));
        file.write(garbage.data(), std::streamsize(garbage.size()));
      }
    }
    ASSERT_TRUE(file.flush());
  }
  Uniform uniform(11);
  int failed = 0;
  for (int k = 0; k < 30; ++k) {
    // Moving towards the second box's corner (2.5, 2.5, 2.5), then about the first box.
    const double t = 1.5 + 0.04 * k;
    const double second[7] = {t, t, t, 1, 0, 0, 0};
    int collides = -1;
    const tetrapage_status status =
        tetrapage_query(near_second, second, TETRAPAGE_ACCURACY_EXACT, 0, 0, &collides);
    if (status != TETRAPAGE_OK) {
      ++failed;
      EXPECT_EQ(status, TETRAPAGE_ERROR_FORMAT) << tetrapage_last_error();
      EXPECT_NE(std::string(tetrapage_last_error()).find(copy.string()), std::string::npos) << tetrapage_last_error();
      EXPECT_NE(std::string(tetrapage_last_error()).find("shard "), std::string::npos) << tetrapage_last_error();
    }
    auto first = random_pose(uniform);
    for (int a = 0; a < 3; ++a) first[a] = uniform(0.2, 1.3);
    ASSERT_EQ(tetrapage_query(near_first, first.data(), TETRAPAGE_ACCURACY_EXACT, 0, 0, &collides), TETRAPAGE_OK)
        << tetrapage_last_error();
    EXPECT_EQ(collides, brute_force(first, geometry::Accuracy::exact()).empty() ? 0 : 1) << "pose " << k;
  }
  EXPECT_GT(failed, 0);
  // The object that failed still answers where the shards are sound.
  const double inside_first[7] = {0.75, 0.75, 0.75, 1, 0, 0, 0};
  int collides = -1;
  EXPECT_EQ(tetrapage_query(near_second, inside_first, TETRAPAGE_ACCURACY_EXACT, 0, 0, &collides), TETRAPAGE_OK)
      << tetrapage_last_error();
  EXPECT_EQ(tetrapage_object_destroy(near_first), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_object_destroy(near_second), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_close(index), TETRAPAGE_OK);
}

}  // namespace
}  // namespace tetrapage
