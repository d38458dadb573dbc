#pragma once
/// @file OrderedPipeline.h
/// Work in parallel, results consumed in order: the shape of the ingest, the in-memory
/// binning and the shard stage.

#include <tbb/parallel_pipeline.h>

#include <algorithm>
#include <cstddef>
#include <optional>
#include <type_traits>
#include <vector>

namespace tetrapage {

// Runs produce(i) for i = 0 .. count - 1 on all threads, at most `in_flight` at once, and
// consume(result) on one thread at a time in the order of i: the shape of the ingest, the
// in-memory binning and the shard stage (work in parallel, results appended in order).
// Results wait in slots of our own, and only their numbers pass through TBB: TBB does not
// destroy the items it holds between filters when an exception cancels the pipeline (every
// result in flight leaked when a write failed). At most `in_flight` tokens live and they are
// consumed in order, so slot i mod in_flight is empty again before token i + in_flight starts.
template <class Produce, class Consume>
void produce_in_parallel_consume_in_order(std::size_t count, std::size_t in_flight,
                                          Produce&& produce, Consume&& consume) {
  using Result = std::invoke_result_t<Produce&, std::size_t>;
  in_flight = std::max<std::size_t>(in_flight, 1);
  std::vector<std::optional<Result>> slots(in_flight);
  std::size_t next = 0;
  tbb::parallel_pipeline(
      in_flight,
      tbb::make_filter<void, std::size_t>(tbb::filter_mode::serial_in_order,
                                          [&](tbb::flow_control& control) -> std::size_t {
                                            if (next == count) control.stop();
                                            return next++;
                                          }) &
          tbb::make_filter<std::size_t, std::size_t>(tbb::filter_mode::parallel,
                                                     [&](std::size_t i) {
                                                       slots[i % in_flight].emplace(produce(i));
                                                       return i;
                                                     }) &
          tbb::make_filter<std::size_t, void>(tbb::filter_mode::serial_in_order,
                                              [&](std::size_t i) {
                                                std::optional<Result>& slot = slots[i % in_flight];
                                                consume(*slot);
                                                slot.reset();
                                              }));
}

}  // namespace tetrapage
