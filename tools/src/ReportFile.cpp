#include "tetrapage/tools/ReportFile.h"

#include <cerrno>
#include <cstring>
#include <fstream>

#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/FileChecks.h"

namespace tetrapage {

void write_report(const std::filesystem::path& path, const nlohmann::json& report) {
  check_outputs(std::span<const std::filesystem::path>(&path, 1), {});
  const auto temporary = std::filesystem::path(path.string() + ".tmp");
  {
    std::ofstream out(temporary);
    if (!out) throw IoError("cannot write report '" + temporary.string() + "'");
    out << report.dump(2) << '\n';
    if (!out.flush()) throw IoError("cannot write report '" + temporary.string() + "'");
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    throw IoError("cannot rename report to '" + path.string() + "': " + ec.message());
  }
}

void check_writable(const std::filesystem::path& path) {
  if (path.empty()) return;
  const auto temporary = std::filesystem::path(path.string() + ".tmp");
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
