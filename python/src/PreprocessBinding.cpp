// tetrapage.preprocess: the pipeline of `tetrapage preprocess`, with its progress told to a
// Python callable, and the run's summary as a dict.

#include <pybind11/functional.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>

#include "Bindings.h"
#include "tetrapage/preprocess/Preprocess.h"

namespace tetrapage::python {

namespace {

// `value` as a T, or an InputError naming the argument (pybind11's cast_error names neither it
// nor the type given).
template <class T>
T cast_argument(py::handle value, const char* what, const char* expected) {
  try {
    return value.cast<T>();
  } catch (const py::cast_error&) {
    throw InputError(std::string(what) + ": " + py::repr(value).cast<std::string>() + " is not " +
                     expected);
  }
}

std::vector<std::filesystem::path> input_paths(py::handle inputs) {
  if (py::isinstance<py::str>(inputs) || py::hasattr(inputs, "__fspath__"))
    return {cast_argument<std::filesystem::path>(inputs, "inputs", "a path")};
  std::vector<std::filesystem::path> paths;
  for (py::handle input : inputs)
    paths.push_back(cast_argument<std::filesystem::path>(input, "inputs", "a path"));
  return paths;
}

struct PreprocessArguments {
  py::handle memory, threads, region_triangles, length_unit, query_extent, spill_folder, progress;
  std::string shard, precision, compression, deflection;
  bool interiors = false, accept_undecided = false;
};

PreprocessOptions options_of(const PreprocessArguments& a) {
  PreprocessOptions options;
  options.memory_bytes = memory_bytes(a.memory, options.memory_bytes);
  if (!a.threads.is_none()) options.threads = unsigned(whole_number(a.threads, "threads", 1, 4096));
  if (!a.region_triangles.is_none())
    options.region_triangles =
        whole_number(a.region_triangles, "region_triangles", 1, std::uint64_t(1) << 32);
  options.shard = parse_shard_choice(a.shard);
  options.precision = parse_stored_precision(a.precision);
  options.compression = parse_chunk_compression(a.compression);
  if (!a.query_extent.is_none()) {
    options.query_extent = cast_argument<double>(a.query_extent, "query_extent", "a length");
    // 0 is the option struct's "automatic": a caller means that with None.
    if (!(options.query_extent > 0) || !std::isfinite(options.query_extent))
      throw InputError("query_extent: " + std::to_string(options.query_extent) +
                       " is not a positive length (None: 5 % of the model's largest side)");
  }
  if (!a.length_unit.is_none())
    options.length_unit = cast_argument<std::string>(a.length_unit, "length_unit", "a unit text");
  if (!a.spill_folder.is_none())
    options.spill_folder =
        cast_argument<std::filesystem::path>(a.spill_folder, "spill_folder", "a path");
  set_deflection(options.tessellation, a.deflection, "deflection");
  options.interiors = a.interiors;
  options.accept_undecided = a.accept_undecided;
  options.progress = a.progress.ptr() == Py_True;
  return options;
}

// Called from the pipeline's threads with the GIL released: takes it to call the user's callable
// (held by the caller's frame for the whole run, so a handle suffices) and to let Ctrl-C stop
// the run (PyErr_CheckSignals acts on the main thread only).
ProgressCallback python_progress(py::handle callable) {
  return [callable](std::string_view label, std::uint64_t done, std::uint64_t total) {
    py::gil_scoped_acquire locked;
    if (callable) callable(std::string(label), done, total);
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  };
}

py::dict run_preprocess(py::handle inputs, const std::filesystem::path& output,
                        const PreprocessArguments& arguments) {
  const std::vector<std::filesystem::path> paths = input_paths(inputs);
  PreprocessOptions options = options_of(arguments);
  const bool callable = !arguments.progress.is_none() && PyCallable_Check(arguments.progress.ptr());
  if (!callable && !arguments.progress.is_none() && !py::isinstance<py::bool_>(arguments.progress))
    throw InputError(
        "progress: give a callable (stage, done, total), True (bars on stderr) or None");
  options.on_progress = python_progress(callable ? arguments.progress : py::handle());
  PreprocessSummary summary;
  {
    py::gil_scoped_release unlocked;
    summary = preprocess(paths, output, options);
  }
  return py::module_::import("json").attr("loads")(summary.to_json());
}

}  // namespace

void bind_preprocess(py::module_& module) {
  module.def(
      "preprocess",
      [](py::handle inputs, const std::filesystem::path& output, py::handle memory,
         py::handle threads, py::handle region_triangles, const std::string& shard,
         const std::string& precision, const std::string& compression, bool interiors,
         bool accept_undecided, py::handle length_unit, const std::string& deflection,
         py::handle query_extent, py::handle spill_folder, py::handle progress) {
        return run_preprocess(
            inputs, output,
            {memory, threads, region_triangles, length_unit, query_extent, spill_folder, progress,
             shard, precision, compression, deflection, interiors, accept_undecided});
      },
      py::arg("inputs"), py::arg("output"), py::kw_only(), py::arg("memory") = py::none(),
      py::arg("threads") = py::none(), py::arg("region_triangles") = py::none(),
      py::arg("shard") = "auto", py::arg("precision") = "exact", py::arg("compression") = "lz4",
      py::arg("interiors") = true, py::arg("accept_undecided") = false,
      py::arg("length_unit") = py::none(), py::arg("deflection") = "0.1%",
      py::arg("query_extent") = py::none(), py::arg("spill_folder") = py::none(),
      py::arg("progress") = py::none(),
      R"(Builds an index from mesh files, STEP/IGES files and manifests (.json), as
`tetrapage preprocess` does, and returns its summary (the --report JSON) as a dict.

inputs: a path or a list of paths. output: the index (.tpi); nothing is left there on failure.
memory: the working-memory budget, bytes or a size ("1G"; k, M, G, T are powers of 1024);
  None: the shared default, tetrapage.DEFAULT_MEMORY (1 GiB). threads: None uses every core.
region_triangles: triangles per region (None: automatic). shard: "auto", "grid", "rtree".
precision: "exact" (answers exact for the input), "double", "float" (rounded: exact for the
  rounded model only). compression: "lz4" or "none". interiors: store which regions lie inside
  closed parts (containment answers; default True, as the CLI). length_unit: the unit of plain
  meshes ("mm", "m").
deflection: STEP/IGES tessellation ("0.1%" of each shape's diagonal, or a length in mm).
progress: a callable(stage, done, total), called from the pipeline's threads at most 10 times
  a second per stage; or True for bars on stderr. What it raises stops the run (Ctrl-C too).
The GIL is released while the pipeline runs.)");
}

}  // namespace tetrapage::python
