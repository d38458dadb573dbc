// DynamicObstacles::save and load. The file is text, one record a line, every number in C's
// "%a" hexadecimal notation for doubles (bit-exact round trip) and decimal for integers:
//
//   tetrapage-dynamic-obstacles 1
//   next_id <id the next insert takes>
//   hidden <count> <part> <part> ...              (the index's hidden parts, ascending)
//   parts <count>
//   then per part:
//   part <id> <name length in bytes>
//   <the name's bytes>                            (a line of its own, any bytes but newline)
//   pose <tx> <ty> <tz> <qw> <qx> <qy> <qz>
//   mesh <vertex count> <triangle count>
//   v <x> <y> <z>                                 (vertex count lines)
//   f <a> <b> <c>                                 (triangle count lines, 0-based vertices)
//   end
//
// Anything else (a wrong magic or version, a missing or extra field, a number that does not
// parse, a count beyond the file) is a FormatError naming the file and the line.

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/QuotedInput.h"
#include "tetrapage/formats/mesh/FileChecks.h"
#include "tetrapage/formats/mesh/OutputFile.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"

namespace tetrapage {

namespace {

constexpr const char* kMagic = "tetrapage-dynamic-obstacles";
constexpr int kVersion = 1;

std::string hex(double x) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%a", x);
  return buffer;
}

void write_part(OutputFile& out, const DynamicObstacles::Part& part) {
  const TriangleSoup& mesh = part.model->mesh;
  out.write("part " + std::to_string(part.id) + ' ' + std::to_string(part.name.size()) + '\n' +
            part.name + '\n');
  std::string pose = "pose";
  for (const double x : part.pose.translation) pose += ' ' + hex(x);
  for (const double x : part.pose.rotation) pose += ' ' + hex(x);
  out.write(pose + "\nmesh " + std::to_string(mesh.vertices.size()) + ' ' +
            std::to_string(mesh.triangles.size()) + '\n');
  for (const auto& v : mesh.vertices)
    out.write("v " + hex(v[0]) + ' ' + hex(v[1]) + ' ' + hex(v[2]) + '\n');
  for (const auto& t : mesh.triangles)
    out.write("f " + std::to_string(t[0]) + ' ' + std::to_string(t[1]) + ' ' +
              std::to_string(t[2]) + '\n');
  out.write("end\n");
}

// save replaces an existing file only when it is empty or an overlay: an index, a mesh or any
// other file of the user's named by mistake is kept.
void require_replaceable(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error) || std::filesystem::file_size(path, error) == 0) return;
  std::ifstream in(path, std::ios::binary);
  std::string start(std::string_view(kMagic).size(), '\0');
  if (!in.read(start.data(), std::streamsize(start.size())) || start != kMagic)
    throw InputError("refusing to write the dynamic obstacles to '" + path.string() +
                     "': it holds something else (an overlay file starts with '" + kMagic + "')");
}

// Reads the file line by line; every failure names the file and the line.
class LineReader {
 public:
  explicit LineReader(const std::filesystem::path& path) : path_(path) {
    require_regular_file(path_);  // a FIFO or /dev/zero would block or grow forever
    in_.open(path_, std::ios::binary);
    if (!in_) throw FormatError(path_.string() + ": cannot open the dynamic obstacles file");
  }
  [[noreturn]] void fail(const std::string& what) const { fail_at(line_, what); }
  [[noreturn]] void fail_at(std::size_t line, const std::string& what) const {
    throw FormatError(path_.string() + ": line " + std::to_string(line) + ": " + what);
  }
  // The next line, which must start with `word`: the rest of it as a stream.
  std::istringstream record(const std::string& word) {
    std::string text = next_line("'" + word + "'");
    std::istringstream fields(text);
    std::string first;
    if (!(fields >> first) || first != word)
      fail("expected '" + word + "', read " + quoted_input(text));
    return fields;
  }
  std::string next_line(const std::string& expected) {
    std::string text;
    if (!bounded_line(text)) fail("the file ends where " + expected + " was expected");
    return text;
  }
  std::size_t line() const { return line_; }
  // Reads `n` numbers of type T from `fields`, then requires the end of the line.
  template <class T>
  void numbers(std::istringstream& fields, T* out, int n) {
    for (int i = 0; i < n; ++i) {
      std::string token;
      if (!(fields >> token)) fail("a number is missing");
      out[i] = parse<T>(token);
    }
    std::string extra;
    if (fields >> extra) fail("unexpected " + quoted_input(extra));
  }
  template <class T>
  T parse(const std::string& token) const {
    char* end = nullptr;
    errno = 0;
    if constexpr (std::is_floating_point_v<T>) {
      const double x = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0') fail(quoted_input(token) + " is not a number");
      return x;
    } else {
      if (token.empty() || token[0] == '-')
        fail(quoted_input(token) + " is not a count or an id");
      const unsigned long long x = std::strtoull(token.c_str(), &end, 10);
      if (end == token.c_str() || *end != '\0' || errno == ERANGE ||
          x > std::numeric_limits<T>::max())
        fail(quoted_input(token) + " is not a count or an id");
      return T(x);
    }
  }
  // Nothing but blank lines may follow the last part.
  void expect_end() {
    std::string text;
    while (bounded_line(text)) {
      if (text.find_first_not_of(" \t\r") != std::string::npos)
        fail("unexpected " + quoted_input(text) + " after the last part");
    }
  }

 private:
  // The longest line the format holds: a name, or a pose of seven "%a" numbers.
  static constexpr std::size_t kMaxLineBytes = kMaxObstacleNameBytes + 1;

  // Reads the next line into `text` (false at the end of the file); a line longer than the
  // format holds fails, so that no input grows memory without bound.
  bool bounded_line(std::string& text) {
    text.clear();
    int c = 0;
    while ((c = in_.get()) != std::char_traits<char>::eof() && c != '\n') {
      if (text.size() == kMaxLineBytes) {
        ++line_;
        fail("the line is longer than " + std::to_string(kMaxLineBytes) + " bytes");
      }
      text += char(c);
    }
    if (c == std::char_traits<char>::eof() && text.empty()) return false;
    ++line_;
    return true;
  }

  std::filesystem::path path_;
  std::ifstream in_;
  std::size_t line_ = 0;
};

// One part's record; its mesh and pose (the part is inserted by the caller).
struct ReadPart {
  std::size_t pose_line = 0;  ///< where the pose stands (insert checks it)
  DynamicPartId id = 0;
  std::string name;
  Pose pose;
  TriangleSoup mesh;
};

ReadPart read_part(LineReader& reader) {
  ReadPart part;
  auto header = reader.record("part");
  std::uint64_t fields[2];
  reader.numbers(header, fields, 2);
  if (fields[0] == 0 || fields[0] >= 0xffffffffu)
    reader.fail("bad part id " + std::to_string(fields[0]));
  part.id = DynamicPartId(fields[0]);
  part.name = reader.next_line("the part's name");
  if (part.name.size() != fields[1])
    reader.fail("the name has " + std::to_string(part.name.size()) + " bytes, not " +
                std::to_string(fields[1]));
  auto pose = reader.record("pose");
  part.pose_line = reader.line();
  double p[7];
  reader.numbers(pose, p, 7);
  part.pose.translation = {p[0], p[1], p[2]};
  part.pose.rotation = {p[3], p[4], p[5], p[6]};
  auto sizes = reader.record("mesh");
  std::uint32_t counts[2];
  reader.numbers(sizes, counts, 2);
  // Counts are not trusted for allocation: a corrupt count ends with the file.
  for (std::uint32_t i = 0; i < counts[0]; ++i) {
    auto v = reader.record("v");
    Vec3 x;
    reader.numbers(v, x.data(), 3);
    if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
      reader.fail("a coordinate is not finite");
    part.mesh.vertices.push_back(x);
  }
  for (std::uint32_t i = 0; i < counts[1]; ++i) {
    auto f = reader.record("f");
    TriangleIndices t;
    reader.numbers(f, t.data(), 3);
    for (const auto corner : t)
      if (corner >= counts[0])
        reader.fail("vertex " + std::to_string(corner) + " is beyond the part's " +
                    std::to_string(counts[0]));
    part.mesh.triangles.push_back(t);
  }
  reader.record("end");
  part.mesh.part_of.assign(part.mesh.triangles.size(), 0);
  part.mesh.part_names = {part.name};
  return part;
}

}  // namespace

void DynamicObstacles::save(const std::filesystem::path& path) const {
  const std::filesystem::path& index_file = index_->path();
  check_outputs(std::span<const std::filesystem::path>(&path, 1),
                std::span<const std::filesystem::path>(&index_file, 1));
  require_replaceable(path);
  OutputFile out(path);
  std::string header = std::string(kMagic) + ' ' + std::to_string(kVersion) + "\nnext_id " +
                       std::to_string(next_id_) + "\nhidden " + std::to_string(hidden_count_);
  for (const std::uint32_t p : hidden_parts()) header += ' ' + std::to_string(p);
  out.write(header + "\nparts " + std::to_string(parts_.size()) + '\n');
  // In id order: the file does not depend on the order of removals.
  std::vector<const Part*> sorted;
  for (const Part& part : parts_) sorted.push_back(&part);
  std::sort(sorted.begin(), sorted.end(),
            [](const Part* a, const Part* b) { return a->id < b->id; });
  for (const Part* part : sorted) write_part(out, *part);
  out.commit();
}

DynamicObstacles DynamicObstacles::load(std::shared_ptr<const CollisionIndex> index,
                                        const std::filesystem::path& path, double cell_size) {
  DynamicObstacles overlay(std::move(index), cell_size);
  LineReader reader(path);
  auto magic = reader.record(kMagic);
  int version = 0;
  reader.numbers(magic, &version, 1);
  if (version != kVersion) reader.fail("unsupported version " + std::to_string(version));
  auto next = reader.record("next_id");
  std::uint32_t next_id = 0;
  reader.numbers(next, &next_id, 1);
  auto hidden = reader.record("hidden");
  std::uint32_t hidden_count = 0;
  hidden >> std::ws;
  {
    std::string token;
    if (!(hidden >> token)) reader.fail("the hidden parts' count is missing");
    hidden_count = reader.parse<std::uint32_t>(token);
  }
  for (std::uint32_t i = 0; i < hidden_count; ++i) {
    std::string token;
    if (!(hidden >> token)) reader.fail("a hidden part is missing");
    const auto part = reader.parse<std::uint32_t>(token);
    if (part >= overlay.hidden_.size())
      reader.fail("hidden part " + std::to_string(part) + " is not a part of the index");
    overlay.hide_part(part);
  }
  auto count = reader.record("parts");
  std::uint32_t parts = 0;
  reader.numbers(count, &parts, 1);
  for (std::uint32_t i = 0; i < parts; ++i) {
    ReadPart part = read_part(reader);
    if (part.id >= next_id || overlay.slot_.count(part.id))
      reader.fail("part id " + std::to_string(part.id) + " repeats or is not below next_id");
    try {
      overlay.next_id_ = part.id;  // the saved id
      overlay.insert(std::move(part.mesh), part.pose, std::move(part.name));
    } catch (const InputError& e) {
      // Lines are checked as they are read: what insert refuses is the pose or the whole mesh.
      reader.fail_at(part.pose_line,
                     std::string("part ") + std::to_string(part.id) + ": " + e.what());
    }
  }
  reader.expect_end();
  overlay.next_id_ = std::max<DynamicPartId>(next_id, 1);
  return overlay;
}

}  // namespace tetrapage
