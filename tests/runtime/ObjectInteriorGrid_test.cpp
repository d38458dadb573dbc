// The closed object's interior grid against CGAL's exact point-in-solid test
// (Side_of_triangle_mesh, exact predicates): every point it classifies, it classifies right,
// including points on cell boundaries and within the margin of the surface; and it classifies
// most points, so the ray-parity fallback stays rare.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <gtest/gtest.h>

#include "tetrapage/runtime/query/ObjectInteriorGrid.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;

struct Case {
  std::uint64_t triangles;
};

class ObjectInteriorGridTest : public ::testing::TestWithParam<Case> {};

TEST_P(ObjectInteriorGridTest, AgreesWithCgalWhereverItAnswers) {
  ObjectOptions options;
  options.triangles = GetParam().triangles;
  static const MeshLibrary library = MeshLibrary::load_default();
  const GeneratedObject object = generate_object(options, &library);
  ASSERT_TRUE(object.closed) << object.source;
  const geometry::ObjectBVH bvh(object.soup);
  // One closed component (the generated objects are one connected closed mesh).
  ClosedComponentOf closed;
  closed.count = 1;
  closed.of_triangle.assign(object.soup.triangle_count(), 0);
  const ObjectInteriorGrid grid(bvh, closed);
  EXPECT_GT(grid.count(ObjectInteriorGrid::Side::inside), 0u) << "a closed object has inside cells";
  EXPECT_GT(grid.count(ObjectInteriorGrid::Side::outside), 0u);

  std::vector<Kernel::Point_3> points;
  std::vector<std::vector<std::size_t>> faces;
  for (const auto& v : object.soup.vertices) points.emplace_back(v[0], v[1], v[2]);
  for (const auto& t : object.soup.triangles) faces.push_back({t[0], t[1], t[2]});
  Mesh mesh;
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, faces, mesh);
  const CGAL::Side_of_triangle_mesh<Mesh, Kernel> side_of(mesh);

  Random random(GetParam().triangles);
  const geometry::Box& box = bvh.bounds();
  int answered = 0, wrong = 0;
  const int samples = 20000;
  for (int i = 0; i < samples; ++i) {
    Vec3 x;
    for (int a = 0; a < 3; ++a) x[a] = random.uniform(box.lo[a], box.hi[a]);
    // A quarter of the points sit on a vertex of the object or on a cell boundary plane.
    if (i % 8 == 0) x = object.soup.vertices[std::size_t(random.uniform(0, double(object.soup.vertices.size()))) %
                                             object.soup.vertices.size()];
    if (i % 8 == 1) x[0] = box.lo[0] + (box.hi[0] - box.lo[0]) * double(i % 5) / double(grid.cells_per_axis());
    const double margin = i % 2 == 0 ? 0.0 : 1e-9;
    const auto side = grid.classify(x, margin);
    if (side == ObjectInteriorGrid::Side::unknown) continue;
    ++answered;
    const auto expected = side_of(Kernel::Point_3(x[0], x[1], x[2]));
    const bool inside = side == ObjectInteriorGrid::Side::inside;
    if (expected == CGAL::ON_BOUNDARY || inside != (expected == CGAL::ON_BOUNDED_SIDE)) {
      if (++wrong <= 5)
        ADD_FAILURE() << "(" << x[0] << ", " << x[1] << ", " << x[2] << "): grid says "
                      << (inside ? "inside" : "outside") << ", CGAL "
                      << (expected == CGAL::ON_BOUNDARY ? "on the surface" : expected == CGAL::ON_BOUNDED_SIDE ? "inside" : "outside");
    }
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(answered, samples / 2) << "the grid should settle most points";
}

INSTANTIATE_TEST_SUITE_P(Objects, ObjectInteriorGridTest, ::testing::Values(Case{116}, Case{2094}, Case{5152}),
                         [](const auto& test) { return "triangles" + std::to_string(test.param.triangles); });

TEST(ObjectInteriorGrid, AnEmptyGridAnswersNothing) {
  const ObjectInteriorGrid grid;
  EXPECT_EQ(grid.classify({0, 0, 0}, 0), ObjectInteriorGrid::Side::unknown);
}

}  // namespace
}  // namespace tetrapage
