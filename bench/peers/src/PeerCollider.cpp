#include "tetrapage/bench/PeerCollider.h"

namespace tetrapage {

const char* to_string(CollisionQuestion question) {
  return question == CollisionQuestion::surfaces ? "surfaces" : "surfaces_or_inside";
}

}  // namespace tetrapage
