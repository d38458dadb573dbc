#pragma once
/// @file ModelRenderer.h
/// A picture of an index (tetrapage render): its stored triangles ray-traced with Embree from
/// outside the model, each coloured by its region's shard (kind, region, or how often a flight
/// paged it in), with a flight path drawn over it (dimmer where the model hides it).

#include <cstdint>
#include <vector>

#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/tools/PngImage.h"

namespace tetrapage {

enum class RenderColouring : std::uint8_t {
  shard_kind,  ///< grid regions blue, R-tree regions orange, each region its own shade
  regions,     ///< a colour per region
  page_ins,    ///< grey never paged in, yellow to red by page-ins (RenderOptions::page_ins)
};

struct RenderOptions {
  std::size_t width = 1200, height = 800;
  double azimuth_degrees = 35;    ///< camera direction around +z, from +x
  double elevation_degrees = 30;  ///< camera direction above the xy plane
  double zoom = 1;                ///< > 1 moves the camera closer
  RenderColouring colouring = RenderColouring::shard_kind;
  std::vector<std::uint32_t> page_ins;  ///< per shard, for RenderColouring::page_ins
  std::vector<Vec3> path;               ///< drawn as a polyline (pose translations)
  /// Above this many triangles, every k-th is drawn (k the smallest that fits), so that
  /// Embree's scene stays within a few GiB for the largest models.
  std::uint64_t max_triangles = 20'000'000;
};

struct RenderSummary {
  std::uint64_t shards = 0;
  std::uint64_t triangles_drawn = 0;
  std::uint64_t stride = 1;  ///< every stride-th triangle drawn
  std::uint64_t pixels_hit = 0;
  double seconds = 0;
};

/// Renders the index's stored triangles (each once, though a shard may repeat a triangle of
/// its neighbour). Reads the shards through the index's cache, one at a time.
/// @throw InputError for a zero size or a page_ins vector of the wrong length; Error if
///        Embree fails.
RgbImage render_model(const CollisionIndex& index, const RenderOptions& options, RenderSummary& summary);

}  // namespace tetrapage
