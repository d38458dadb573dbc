#include "tetrapage/tools/AnswerFile.h"

#include <fstream>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/QuotedInput.h"
#include "tetrapage/formats/mesh/FileChecks.h"
#include "tetrapage/formats/mesh/OutputFile.h"

namespace tetrapage {

void write_answers(const std::filesystem::path& path, std::span<const std::uint8_t> collides) {
  OutputFile out(path);
  out.write("step,collides\n");
  for (std::size_t i = 0; i < collides.size(); ++i)
    out.write(std::to_string(i) + (collides[i] ? ",1\n" : ",0\n"));
  out.commit();
}

std::vector<std::uint8_t> read_answers(const std::filesystem::path& path) {
  require_regular_file(path);  // a FIFO would block the read forever
  std::ifstream in(path);
  if (!in) throw IoError("cannot open answers file '" + path.string() + "'");
  std::string line;
  if (!std::getline(in, line) || (line != "step,collides" && line != "step,collides\r"))
    throw FormatError("answers file '" + path.string() + "' line 1: expected header 'step,collides'");
  std::vector<std::uint8_t> answers;
  std::size_t line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const auto comma = line.find(',');
    const std::string where =
        "answers file '" + path.string() + "' line " + std::to_string(line_number) + ": ";
    if (comma == std::string::npos)
      throw FormatError(where + "expected 'step,collides', got " + quoted_input(line));
    const std::string step = line.substr(0, comma), value = line.substr(comma + 1);
    if (step != std::to_string(answers.size()))
      throw FormatError(where + "step " + quoted_input(step) + " out of sequence (expected " +
                        std::to_string(answers.size()) + ")");
    if (value != "0" && value != "1")
      throw FormatError(where + "collides must be 0 or 1, got " + quoted_input(value));
    answers.push_back(value == "1" ? 1 : 0);
  }
  return answers;
}

}  // namespace tetrapage
