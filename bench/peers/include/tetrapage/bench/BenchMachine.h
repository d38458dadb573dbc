#pragma once
// What a peer benchmark ran on and with: the processor, its cores and load, and the compiler
// and flags of every binary it timed, so that a figure can be read against the machine and
// each peer's build (bench-peers states them in every report).

#include <nlohmann/json.hpp>
#include <string>

namespace tetrapage::bench {

/// The processor (model name), its logical cores, the memory, the kernel, and the load average
/// (1, 5, 15 minutes) now.
nlohmann::json machine_description();

/// Per timed code: tetrapage, CGAL (header-only, so with tetrapage's flags) and the harness
/// with this build's compiler and flags; FCL and Embree as the shared libraries they are
/// (their package, version and the distribution's build flags).
nlohmann::json build_description();

/// The load average (1, 5, 15 minutes) now, as /proc/loadavg gives it.
std::string load_average();

}  // namespace tetrapage::bench
