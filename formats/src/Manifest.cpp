// Assembly manifests: parsing with every error located by its JSON path, and placing the
// instances of each part (read once) into one soup.

#include "tetrapage/formats/Manifest.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "PathSupport.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/FileChecks.h"
#include "tetrapage/formats/MeshReader.h"

namespace tetrapage {

Transform identity_transform() {
  return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
}

double metres_per_unit(const std::string& unit) {
  static const std::map<std::string, double, std::less<>> units = {
      {"m", 1.0}, {"cm", 0.01}, {"mm", 0.001}, {"um", 1e-6}, {"in", 0.0254}, {"ft", 0.3048}};
  const auto found = units.find(unit);
  if (found == units.end()) {
    throw InputError("unknown unit '" + unit + "' (known: m, cm, mm, um, in, ft)");
  }
  return found->second;
}

namespace {

using nlohmann::json;

/// Where we are in the manifest, for messages: "file: parts[2].instances[0].matrix: ".
class JsonPlace {
 public:
  JsonPlace(const std::string& file, std::string path) : file_(file), path_(std::move(path)) {}
  JsonPlace operator[](std::size_t index) const {
    return {file_, path_ + "[" + std::to_string(index) + "]"};
  }
  JsonPlace field(const std::string& key) const {
    return {file_, path_.empty() ? key : path_ + "." + key};
  }
  [[noreturn]] void format_error(const std::string& what) const {
    throw FormatError(file_ + ": " + (path_.empty() ? std::string("top level") : path_) + ": " +
                      what);
  }
  [[noreturn]] void input_error(const std::string& what) const {
    throw InputError(file_ + ": " + (path_.empty() ? std::string("top level") : path_) + ": " +
                     what);
  }

 private:
  const std::string& file_;
  std::string path_;
};

/// At most 57 bytes of `text`, not splitting a UTF-8 character (the parser checked it).
std::string cut(const std::string& text, bool& was_cut) {
  was_cut = text.size() > 57;
  if (!was_cut) return text;
  std::size_t end = 57;
  while (end > 0 && (static_cast<unsigned char>(text[end]) & 0xc0) == 0x80) --end;
  return text.substr(0, end);
}

/// A string as JSON writes it (so a message stays one line), cut short.
std::string escaped(const std::string& text) {
  bool was_cut = false;
  const std::string json_text = json(cut(text, was_cut)).dump(-1, ' ', false, json::error_handler_t::replace);
  return json_text.substr(1, json_text.size() - 2) + (was_cut ? "..." : "");
}

/// `text` escaped between two `quote` characters. Built by append: GCC 12 warns falsely
/// (-Wrestrict) on "'" + std::string(...).
std::string between(char quote, const std::string& text) {
  std::string result(1, quote);
  result.append(escaped(text));
  result.push_back(quote);
  return result;
}

/// A name from the file, quoted for a message: 'name'.
std::string in_quotes(const std::string& text) { return between('\'', text); }

/// A short description of a value for a message: arrays and objects by their size (printing
/// them costs as much as they hold), strings cut (fuzz_manifest: cutting the printed text
/// could split a character, which dump() then refused), numbers as they are.
std::string shown(const json& value) {
  if (value.is_array()) return "an array of " + std::to_string(value.size()) + " values";
  if (value.is_object()) return "an object of " + std::to_string(value.size()) + " fields";
  if (value.is_string()) return between('"', value.get_ref<const std::string&>());
  return value.dump(-1, ' ', false, json::error_handler_t::replace);
}

/// Deeper nesting than any manifest needs is refused while parsing: the parse itself is
/// iterative, but what follows (messages, copies) need not be.
constexpr int kMaxJsonDepth = 64;

/// Thrown by the parser callback, caught in read_manifest.
struct TooDeep {
  int depth = 0;
};

void require_keys(const json& object, const JsonPlace& place,
                  std::initializer_list<std::string_view> allowed) {
  if (!object.is_object()) place.format_error("expected an object, got " + shown(object));
  for (const auto& item : object.items()) {
    if (std::find(allowed.begin(), allowed.end(), item.key()) == allowed.end()) {
      std::string list;
      for (const auto key : allowed) list += (list.empty() ? "" : ", ") + std::string(key);
      place.format_error("unknown field " + in_quotes(item.key()) + " (allowed: " + list + ")");
    }
  }
}

double number(const json& value, const JsonPlace& place) {
  if (!value.is_number()) place.format_error("expected a number, got " + shown(value));
  const double result = value.get<double>();
  if (!std::isfinite(result)) place.input_error("not finite: " + shown(value));
  return result;
}

std::vector<double> numbers(const json& value, const JsonPlace& place, std::size_t count) {
  if (!value.is_array() || value.size() != count) {
    place.format_error("expected an array of " + std::to_string(count) + " numbers, got " +
                       shown(value));
  }
  std::vector<double> result;
  for (std::size_t i = 0; i < count; ++i) result.push_back(number(value[i], place[i]));
  return result;
}

std::string text(const json& value, const JsonPlace& place) {
  if (!value.is_string()) place.format_error("expected a string, got " + shown(value));
  return value.get<std::string>();
}

double unit_of(const json& value, const JsonPlace& place) {
  const std::string unit = text(value, place);
  try {
    return metres_per_unit(unit);
  } catch (const InputError&) {
    place.input_error("unknown unit " + in_quotes(unit) + " (known: m, cm, mm, um, in, ft)");
  }
}

double determinant3(const Transform& m) {
  return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
         m[2] * (m[4] * m[9] - m[5] * m[8]);
}

Transform parse_instance(const json& instance, const JsonPlace& place) {
  require_keys(instance, place, {"matrix", "translation", "rotation", "scale"});
  Transform transform = identity_transform();
  if (instance.contains("matrix")) {
    if (instance.contains("translation") || instance.contains("rotation") ||
        instance.contains("scale")) {
      place.format_error("give either 'matrix' or 'translation'/'rotation'/'scale', not both");
    }
    const auto values = numbers(instance["matrix"], place.field("matrix"), 16);
    std::copy(values.begin(), values.end(), transform.begin());
    if (transform[12] != 0 || transform[13] != 0 || transform[14] != 0 || transform[15] != 1) {
      place.field("matrix").input_error("the last row must be 0 0 0 1 (an affine transform)");
    }
  } else {
    Vec3 scale{1, 1, 1};
    if (instance.contains("scale")) {
      const json& value = instance["scale"];
      const JsonPlace scale_place = place.field("scale");
      if (value.is_number()) {
        scale.fill(number(value, scale_place));
      } else {
        const auto values = numbers(value, scale_place, 3);
        std::copy(values.begin(), values.end(), scale.begin());
      }
    }
    std::array<double, 4> q{1, 0, 0, 0};
    if (instance.contains("rotation")) {
      const JsonPlace rotation_place = place.field("rotation");
      const auto values = numbers(instance["rotation"], rotation_place, 4);
      const double norm = std::sqrt(values[0] * values[0] + values[1] * values[1] +
                                    values[2] * values[2] + values[3] * values[3]);
      if (!(norm > 0) || !std::isfinite(norm)) {
        rotation_place.input_error("the quaternion (qw, qx, qy, qz) cannot be normalised");
      }
      for (int k = 0; k < 4; ++k) q[k] = values[k] / norm;
    }
    Vec3 translation{0, 0, 0};
    if (instance.contains("translation")) {
      const auto values = numbers(instance["translation"], place.field("translation"), 3);
      std::copy(values.begin(), values.end(), translation.begin());
    }
    // x -> R (S x) + t: scale in the part's frame, then rotate, then place.
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    const double rotation[9] = {
        1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
        2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
        2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
    for (int row = 0; row < 3; ++row) {
      for (int column = 0; column < 3; ++column)
        transform[4 * row + column] = rotation[3 * row + column] * scale[column];
      transform[4 * row + 3] = translation[row];
    }
  }
  for (const double value : transform) {
    if (!std::isfinite(value)) place.input_error("the transform is not finite");
  }
  const double determinant = determinant3(transform);
  if (determinant == 0 || !std::isfinite(determinant)) {
    place.input_error("the transform is singular (it flattens the part)");
  }
  return transform;
}

}  // namespace

bool is_manifest_path(const std::filesystem::path& path) {
  return detail::lower_extension(path) == ".json";
}

Manifest read_manifest(const std::filesystem::path& path) {
  const std::string file = path.string();
  require_regular_file(path);  // a FIFO would block the read forever
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw IoError("cannot open manifest '" + file + "': " + std::strerror(errno));
  json document;
  try {
    // The callback sees each array or object open, with the number already open around it.
    const json::parser_callback_t limit_depth = [](int depth, json::parse_event_t event, json&) {
      if ((event == json::parse_event_t::object_start || event == json::parse_event_t::array_start) &&
          depth + 1 > kMaxJsonDepth)
        throw TooDeep{depth + 1};
      return true;
    };
    // Comments are allowed, so a manifest can explain itself.
    document = json::parse(stream, limit_depth, true, true);
  } catch (const TooDeep& deep) {
    throw FormatError(file + ": arrays and objects nested deeper than " + std::to_string(kMaxJsonDepth) +
                      " levels (depth " + std::to_string(deep.depth) + "); a manifest needs 6");
  } catch (const json::exception& error) {
    // A syntax error, or a number beyond double's range (out_of_range, found by fuzzing). Its
    // text quotes the token read last, which can be as long as the file.
    std::string what = error.what();
    if (what.size() > 200) what = what.substr(0, 197) + "...";
    throw FormatError(file + ": not valid JSON: " + what);
  }
  if (stream.bad()) throw IoError("cannot read manifest '" + file + "'");

  const JsonPlace root(file, "");
  require_keys(document, root, {"units", "parts"});
  Manifest manifest;
  manifest.path = path;
  double assembly_metres = 1.0;
  if (document.contains("units")) {
    manifest.units = text(document["units"], root.field("units"));
    assembly_metres = unit_of(document["units"], root.field("units"));
  }
  if (!document.contains("parts")) root.format_error("missing field 'parts'");
  const json& parts = document["parts"];
  const JsonPlace parts_place = root.field("parts");
  if (!parts.is_array()) parts_place.format_error("expected an array, got " + shown(parts));
  if (parts.empty()) parts_place.input_error("the assembly has no part");

  const std::filesystem::path folder = path.parent_path();
  std::map<std::string, std::size_t> names;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const json& part = parts[i];
    const JsonPlace place = parts_place[i];
    require_keys(part, place, {"name", "file", "units", "instances"});
    ManifestPart result;
    if (!part.contains("file")) place.format_error("missing field 'file'");
    const std::filesystem::path part_file = text(part["file"], place.field("file"));
    if (part_file.empty()) place.field("file").format_error("empty file name");
    result.file = part_file.is_absolute() ? part_file : folder / part_file;
    result.name =
        part.contains("name") ? text(part["name"], place.field("name")) : part_file.stem().string();
    if (result.name.empty()) place.field("name").format_error("empty part name");
    if (const auto [it, inserted] = names.emplace(result.name, i); !inserted) {
      place.field("name").input_error("duplicate part name " + in_quotes(result.name) + " (also parts[" +
                                      std::to_string(it->second) + "]; give each part a name)");
    }
    if (part.contains("units")) {
      result.unit_scale = unit_of(part["units"], place.field("units")) / assembly_metres;
    }
    if (part.contains("instances")) {
      const json& instances = part["instances"];
      const JsonPlace instances_place = place.field("instances");
      if (!instances.is_array()) {
        instances_place.format_error("expected an array, got " + shown(instances));
      }
      if (instances.empty()) {
        instances_place.format_error("empty (leave 'instances' out to place the part once)");
      }
      for (std::size_t k = 0; k < instances.size(); ++k)
        result.instances.push_back(parse_instance(instances[k], instances_place[k]));
    } else {
      result.instances.push_back(identity_transform());
    }
    manifest.parts.push_back(std::move(result));
  }
  return manifest;
}

TriangleSoup load_assembly(const Manifest& manifest, std::vector<ReadReport>* reports,
                           Progress& progress, const TessellationOptions& tessellation) {
  TriangleSoup assembly;
  for (const ManifestPart& part : manifest.parts) {
    ReadReport report;
    const TriangleSoup source = read_mesh(part.file, &report, tessellation);
    const std::string stem = part.file.stem().string();
    for (std::size_t k = 0; k < part.instances.size(); ++k) {
      const Transform& m = part.instances[k];
      const std::string label =
          part.instances.size() == 1 ? part.name : part.name + "#" + std::to_string(k);
      if (assembly.vertices.size() + source.vertices.size() >
          std::numeric_limits<std::uint32_t>::max()) {
        throw InputError(manifest.path.string() + ": part '" + label +
                         "': the assembly has more vertices than a soup can index");
      }
      const auto vertex_base = static_cast<std::uint32_t>(assembly.vertices.size());
      const auto part_base = static_cast<std::uint32_t>(assembly.part_names.size());
      for (const auto& name : source.part_names) {
        // A file of several parts (glTF nodes, named "stem/node") keeps its node names.
        std::string sub = name.starts_with(stem + "/") ? name.substr(stem.size() + 1) : name;
        assembly.part_names.push_back(source.part_count() == 1 ? label : label + "/" + sub);
      }
      for (const Vec3& p : source.vertices) {
        const Vec3 s{p[0] * part.unit_scale, p[1] * part.unit_scale, p[2] * part.unit_scale};
        Vec3 placed;
        for (int row = 0; row < 3; ++row)
          placed[row] =
              (m[4 * row] * s[0] + m[4 * row + 1] * s[1] + m[4 * row + 2] * s[2]) + m[4 * row + 3];
        if (!std::isfinite(placed[0]) || !std::isfinite(placed[1]) || !std::isfinite(placed[2])) {
          throw InputError(manifest.path.string() + ": part '" + label +
                           "': placing it overflows the coordinates");
        }
        assembly.vertices.push_back(placed);
      }
      for (std::size_t t = 0; t < source.triangles.size(); ++t) {
        const auto& tri = source.triangles[t];
        const TriangleIndices placed{tri[0] + vertex_base, tri[1] + vertex_base,
                                     tri[2] + vertex_base};
        // Rounding in the placement can flatten a sliver: drop it like the reader would.
        if (is_degenerate_triangle(assembly.vertices[placed[0]], assembly.vertices[placed[1]],
                                   assembly.vertices[placed[2]])) {
          ++report.degenerate_dropped;
          continue;
        }
        assembly.triangles.push_back(placed);
        assembly.part_of.push_back(part_base + source.part_of[t]);
      }
    }
    if (reports != nullptr) reports->push_back(std::move(report));
    progress.advance(1);
  }
  return assembly;
}

std::vector<InputPiece> input_pieces(const std::vector<std::filesystem::path>& inputs) {
  std::vector<InputPiece> pieces;
  for (const auto& input : inputs) {
    if (!is_manifest_path(input)) {
      pieces.push_back({input, nullptr, 0});
      continue;
    }
    const auto manifest = std::make_shared<const Manifest>(read_manifest(input));
    for (std::size_t p = 0; p < manifest->parts.size(); ++p) pieces.push_back({input, manifest, p});
  }
  return pieces;
}

TriangleSoup load_input_piece(const InputPiece& piece, std::vector<ReadReport>* reports,
                              const TessellationOptions& tessellation) {
  if (!piece.manifest) {
    ReadReport report;
    TriangleSoup soup = read_mesh(piece.input, &report, tessellation);
    if (reports != nullptr) reports->push_back(std::move(report));
    return soup;
  }
  Manifest single;
  single.path = piece.manifest->path;
  single.units = piece.manifest->units;
  single.parts = {piece.manifest->parts.at(piece.part)};
  return load_assembly(single, reports, Progress::silent(), tessellation);
}

TriangleSoup load_inputs(const std::vector<std::filesystem::path>& inputs,
                         std::vector<ReadReport>* reports, Progress& progress,
                         const TessellationOptions& tessellation) {
  TriangleSoup all;
  for (const auto& input : inputs) {
    TriangleSoup soup;
    if (is_manifest_path(input)) {
      soup = load_assembly(read_manifest(input), reports, progress, tessellation);
    } else {
      ReadReport report;
      soup = read_mesh(input, &report, tessellation);
      if (reports != nullptr) reports->push_back(std::move(report));
      progress.advance(1);
    }
    if (all.vertices.size() + soup.vertices.size() > std::numeric_limits<std::uint32_t>::max()) {
      throw InputError(input.string() + ": the inputs have more vertices than a soup can index");
    }
    if (all.part_names.empty() && all.vertices.empty()) {
      all = std::move(soup);
    } else {
      all.append(soup);
    }
  }
  return all;
}

}  // namespace tetrapage
