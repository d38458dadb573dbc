// STEP and IGES read whole (TessellatedFile.cpp reads and places), and the options' text.

#include "tetrapage/formats/mesh/CadReader.h"

#include <chrono>
#include <cmath>

#include "CadModule.h"
#include "PathSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/TessellatedFile.h"

namespace tetrapage {

namespace detail {

bool is_iges_path(const std::filesystem::path& path) {
  const std::string extension = lower_extension(path);
  return extension == ".iges" || extension == ".igs";
}

}  // namespace detail

void set_deflection(TessellationOptions& options, const std::string& text, std::string_view what) {
  std::string number = text;
  const bool relative = !number.empty() && number.back() == '%';
  if (relative) number.pop_back();
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(number, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != number.size() || number.empty() || !(value > 0) || !std::isfinite(value))
    throw InputError(std::string(what) + " '" + text +
                     "': expected a positive length (0.01) or percentage (0.1%)");
  options.relative_deflection = relative;
  options.deflection = relative ? value / 100 : value;
}

bool is_cad_path(const std::filesystem::path& path) {
  const std::string extension = detail::lower_extension(path);
  return extension == ".step" || extension == ".stp" || extension == ".p21" || detail::is_iges_path(path);
}

TriangleSoup read_cad(const std::filesystem::path& path, const TessellationOptions& options,
                      ReadReport* report) {
  const auto start = std::chrono::steady_clock::now();
  ReadReport local;
  ReadReport& out = report != nullptr ? *report : local;
  const TessellatedFile file(path, options, out);
  TriangleSoup soup = file.place(out);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return soup;
}

}  // namespace tetrapage
