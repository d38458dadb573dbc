#pragma once
/// @file StudyCollider.h
/// One of the study's four methods (study/StudyMethod.h) as a collider of the benchmarks:
/// the object placed with its hull box, then the method's two-phase check; its counters
/// (full checks, cells, nodes, tets) add up over the flight.

#include <memory>

#include "tetrapage/bench/PeerCollider.h"
#include "tetrapage/study/StudyMethod.h"

namespace tetrapage {

class StudyCollider final : public PeerCollider {
 public:
  /// The method is shared: the benchmark builds it once per environment and flies every
  /// object through it.
  StudyCollider(std::shared_ptr<study::StudyMethod> method, const TriangleSoup& object)
      : method_(std::move(method)), object_(object) {}

  std::string description() const override {
    return "study " + method_->name() + " (" + method_->parameters() + "), exact";
  }
  CollisionQuestion question() const override { return CollisionQuestion::surfaces; }
  bool collides(const Pose& pose) override {
    object_.place(pose);
    return method_->collides(object_, counters_);
  }
  std::uint64_t structure_bytes() const override { return method_->statistics().bytes; }

  const study::StudyMethod& method() const { return *method_; }
  const study::StudyCounters& counters() const { return counters_; }

 private:
  std::shared_ptr<study::StudyMethod> method_;
  study::PlacedObject object_;
  study::StudyCounters counters_;
};

}  // namespace tetrapage
