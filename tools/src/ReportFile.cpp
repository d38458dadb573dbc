#include "tetrapage/tools/ReportFile.h"

#include <cerrno>
#include <cstring>
#include <fstream>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/FileChecks.h"
#include "tetrapage/formats/mesh/OutputFile.h"

namespace tetrapage {

void write_report(const std::filesystem::path& path, const nlohmann::json& report) {
  OutputFile out(path);
  out.write(report.dump(2) + '\n');
  out.commit();
}

void check_writable(const std::filesystem::path& path) {
  if (path.empty()) return;
  const std::filesystem::path temporary = temporary_path(path);
  {
    std::ofstream probe(temporary);
    if (!probe)
      throw IoError("cannot write '" + path.string() + "': " + std::strerror(errno));
  }
  std::error_code ec;
  std::filesystem::remove(temporary, ec);
}

void check_outputs_writable(std::span<const std::filesystem::path> outputs,
                            std::span<const std::filesystem::path> inputs) {
  check_outputs(outputs, inputs);
  for (const auto& output : outputs) check_writable(output);
}

}  // namespace tetrapage
