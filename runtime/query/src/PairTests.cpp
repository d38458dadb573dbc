#include "PairTests.h"

#include "ContainmentCheck.h"

namespace tetrapage {

bool holds_a_component(const PairSide& outer, const PairSide& inner) {
  if (!outer.model.closed) return false;
  for (const std::uint32_t v : inner.model.component_vertices) {
    const geometry::Point& p = inner.placed.world_vertex(v);
    if (!geometry::box_contains(outer.world_box, p)) continue;
    switch (outer.model.interior_grid.classify(outer.placed.to_object_frame(p),
                                               outer.placed.frame_margin(p))) {
      case ObjectInteriorGrid::Side::inside:
        return true;
      case ObjectInteriorGrid::Side::outside:
        break;
      case ObjectInteriorGrid::Side::unknown:
        if (crossing_parity_holds(outer.model, outer.placed, p, outer.world_box)) return true;
        break;
    }
  }
  return false;
}

}  // namespace tetrapage
