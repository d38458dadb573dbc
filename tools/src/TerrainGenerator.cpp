#include "tetrapage/tools/TerrainGenerator.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {
namespace {

// About 24 MB of vertices and triangles per band: a 1201 x 1201 terrain takes three bands.
constexpr std::uint64_t band_triangle_limit = std::uint64_t{1} << 20;

// A square fractal heightfield by diamond-square; floats, since the heights are rescaled
// afterwards and a large grid must stay small in memory.
class FractalGrid {
 public:
  FractalGrid(std::size_t side, double roughness, Random& random)
      : side_(side), heights_(side * side, 0.0f) {
    const std::size_t last = side - 1;
    for (std::size_t y : {std::size_t{0}, last})
      for (std::size_t x : {std::size_t{0}, last}) at(x, y) = float(random.uniform(-1.0, 1.0));
    const double decay = std::pow(2.0, -roughness);
    double amplitude = decay;
    for (std::size_t step = last; step > 1; step /= 2) {
      const std::size_t half = step / 2;
      // Diamond step: the centre of each square from its four corners.
      for (std::size_t y = half; y < side; y += step)
        for (std::size_t x = half; x < side; x += step) {
          const double mean = 0.25 * (double(at(x - half, y - half)) + at(x + half, y - half) +
                                      at(x - half, y + half) + at(x + half, y + half));
          at(x, y) = float(mean + amplitude * random.uniform(-1.0, 1.0));
        }
      // Square step: each edge midpoint from its (up to four) diamond neighbours.
      for (std::size_t y = 0; y < side; y += half) {
        const std::size_t first = (y / half) % 2 == 0 ? half : 0;
        for (std::size_t x = first; x < side; x += step) {
          double sum = 0.0;
          int count = 0;
          const auto add = [&](std::size_t nx, std::size_t ny) {
            sum += at(nx, ny);
            ++count;
          };
          if (x >= half) add(x - half, y);
          if (x + half < side) add(x + half, y);
          if (y >= half) add(x, y - half);
          if (y + half < side) add(x, y + half);
          at(x, y) = float(sum / count + amplitude * random.uniform(-1.0, 1.0));
        }
      }
      amplitude *= decay;
    }
  }

  float at(std::size_t x, std::size_t y) const { return heights_[y * side_ + x]; }

 private:
  float& at(std::size_t x, std::size_t y) { return heights_[y * side_ + x]; }

  std::size_t side_;
  std::vector<float> heights_;
};

// Bilinear samples of a square window of the fractal grid at s x s evenly spaced points.
class Sampler {
 public:
  Sampler(const FractalGrid& grid, std::size_t offset_x, std::size_t offset_y,
          std::size_t source_side, std::size_t samples)
      : grid_(grid),
        offset_x_(offset_x),
        offset_y_(offset_y),
        last_(source_side - 1),
        ratio_(double(source_side - 1) / double(samples - 1)) {}

  double height(std::size_t i, std::size_t j) const {
    const auto [x0, fx] = split(i);
    const auto [y0, fy] = split(j);
    const std::size_t x1 = std::min(x0 + 1, last_), y1 = std::min(y0 + 1, last_);
    const double h00 = grid_.at(offset_x_ + x0, offset_y_ + y0);
    const double h10 = grid_.at(offset_x_ + x1, offset_y_ + y0);
    const double h01 = grid_.at(offset_x_ + x0, offset_y_ + y1);
    const double h11 = grid_.at(offset_x_ + x1, offset_y_ + y1);
    return (1 - fy) * ((1 - fx) * h00 + fx * h10) + fy * ((1 - fx) * h01 + fx * h11);
  }

 private:
  std::pair<std::size_t, double> split(std::size_t i) const {
    const double position = double(i) * ratio_;
    const auto cell = std::min(static_cast<std::size_t>(position), last_);
    return {cell, position - double(cell)};
  }

  const FractalGrid& grid_;
  std::size_t offset_x_, offset_y_, last_;
  double ratio_;
};

void check_options(const TerrainOptions& options) {
  if (options.triangles == 0 || options.triangles > max_terrain_triangles)
    throw InputError("terrain: --triangles " + std::to_string(options.triangles) +
                     " is out of range [1, " + std::to_string(max_terrain_triangles) + "]");
  if (!(options.roughness >= 0.0) || !(options.roughness <= 4.0))
    throw InputError("terrain: roughness " + std::to_string(options.roughness) +
                     " is out of range [0, 4]");
  if (!std::isfinite(options.slab_low) || !std::isfinite(options.slab_high) ||
      !(options.slab_low < options.slab_high))
    throw InputError("terrain: height slab [" + std::to_string(options.slab_low) + ", " +
                     std::to_string(options.slab_high) + "] is empty or not finite");
}

}  // namespace

std::size_t terrain_samples_per_side(std::uint64_t triangles) {
  const auto guess = static_cast<std::uint64_t>(std::sqrt(double(triangles) / 2.0));
  std::uint64_t best = 1;
  std::uint64_t best_error = ~std::uint64_t{0};
  for (std::uint64_t m = guess > 1 ? guess - 1 : 1; m <= guess + 2; ++m) {
    const std::uint64_t count = 2 * m * m;
    const std::uint64_t error = count > triangles ? count - triangles : triangles - count;
    if (error < best_error) {
      best = m;
      best_error = error;
    }
  }
  return static_cast<std::size_t>(best + 1);
}

TerrainSummary generate_terrain(const TerrainOptions& options, MeshWriter& writer,
                                Progress& progress) {
  check_options(options);
  Random random(options.seed);
  TerrainSummary summary;
  const std::size_t s = terrain_samples_per_side(options.triangles);
  summary.samples_per_side = s;
  summary.source_side = std::max(dem_grid_side, s);
  summary.fractal_side = 3;
  while (summary.fractal_side < summary.source_side)
    summary.fractal_side = 2 * (summary.fractal_side - 1) + 1;

  const FractalGrid grid(summary.fractal_side, options.roughness, random);
  const std::size_t spare = summary.fractal_side - summary.source_side;
  const std::size_t offset_x = random.below(spare + 1);
  const std::size_t offset_y = random.below(spare + 1);
  const Sampler sampler(grid, offset_x, offset_y, summary.source_side, s);

  double lowest = 1e300, highest = -1e300;
  for (std::size_t j = 0; j < s; ++j)
    for (std::size_t i = 0; i < s; ++i) {
      const double h = sampler.height(i, j);
      lowest = std::min(lowest, h);
      highest = std::max(highest, h);
    }
  const double range = highest > lowest ? highest - lowest : 1.0;
  const double thickness = options.slab_high - options.slab_low;
  const auto z_of = [&](double h) {
    return std::clamp(options.slab_low + (h - lowest) / range * thickness, options.slab_low,
                      options.slab_high);
  };

  const std::size_t cells = s - 1;
  const std::size_t rows_per_band =
      std::max<std::size_t>(1, std::size_t(band_triangle_limit / (2 * cells)));
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  for (std::size_t first_row = 0; first_row < cells; first_row += rows_per_band) {
    const std::size_t end_row = std::min(cells, first_row + rows_per_band);
    vertices.clear();
    triangles.clear();
    // Exact sizes: growing by doubling would briefly hold twice the band.
    vertices.reserve((end_row - first_row + 1) * s);
    triangles.reserve(2 * (end_row - first_row) * cells);
    for (std::size_t j = first_row; j <= end_row; ++j)
      for (std::size_t i = 0; i < s; ++i)
        vertices.push_back(
            {double(i) / double(cells), double(j) / double(cells), z_of(sampler.height(i, j))});
    const auto index = [&](std::size_t i, std::size_t j) {
      return static_cast<std::uint32_t>((j - first_row) * s + i);
    };
    for (std::size_t j = first_row; j < end_row; ++j)
      for (std::size_t i = 0; i < cells; ++i) {
        // Counter-clockwise seen from above: normals point up.
        triangles.push_back({index(i, j), index(i + 1, j), index(i + 1, j + 1)});
        triangles.push_back({index(i, j), index(i + 1, j + 1), index(i, j + 1)});
      }
    // One surface, so one part: a reader finds its components across the bands' seams.
    if (first_row == 0) {
      writer.add_part(vertices, triangles, "terrain");
    } else {
      writer.extend_part(vertices, triangles);
    }
    for (const auto& v : vertices) summary.bounds.extend(v);
    summary.vertices += vertices.size();
    summary.triangles += triangles.size();
    summary.bands += 1;
    progress.advance(triangles.size());
  }
  return summary;
}

}  // namespace tetrapage
