#pragma once
// Reading a CAD file in a child process: OpenCASCADE runs there, so that its crash, endless
// loop or runaway allocation ends the child, not the caller, and becomes an error naming the
// file. The child sends back the tessellated shapes and their instances; the caller places
// them as an in-process read does.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/Manifest.h"

namespace tetrapage::detail {

/// A distinct shape of a CAD file, tessellated in its own frame.
struct TessellatedShape {
  std::string name;
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  double deflection = 0;  // the absolute deflection asked for
  std::string error;      // why it could not be tessellated
  bool refused = false;   // the error is a limit (not a failure --skip-bad-parts may skip)
};

/// A placed instance of a shape: x -> R x + t, as a manifest's instances.
struct ShapeInstance {
  std::size_t shape = 0;
  Transform placement{};
  std::string path;
};

/// What a CAD file holds once read and tessellated, before its instances are placed.
struct CadContent {
  std::vector<TessellatedShape> shapes;
  std::vector<ShapeInstance> instances;
};

/// The child's limits.
struct IsolationLimits {
  /// Address space the child may add to what it inherits, in bytes (0: the machine's memory).
  std::uint64_t memory_bytes = 0;
  /// Seconds before the child is killed (0: no limit).
  double seconds = 0;
  /// The library the child runs, named when the child dies of a signal.
  const char* library = "OpenCASCADE";
};

/// Runs `read` in a child process made by fork() and returns what it read. The child runs
/// only `read` and our own serialisation, then _exit()s; it must not use TBB (its workers do
/// not survive fork) or anything the caller's other threads may hold locked.
/// @throw the Error `read` threw (same class and message); FormatError when the child dies of
///        a signal; InputError when it exceeds a limit; IoError when no child can be made.
CadContent read_in_child(const std::string& file, const IsolationLimits& limits,
                         const std::function<CadContent()>& read);

/// The machine's physical memory, in bytes (8 GiB when the system does not say): the child's
/// memory when no limit is given.
std::uint64_t machine_memory();

/// Whether the address-space limit is applied: not under AddressSanitizer or ThreadSanitizer,
/// whose shadow memory reserves terabytes.
bool memory_limit_applies();

}  // namespace tetrapage::detail
