// Assembly manifests: parsing with every error located by its JSON path, and placing the
// instances of each part (read once) into one soup.

#include "tetrapage/formats/mesh/Manifest.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <span>
#include <sstream>

#include <nlohmann/json.hpp>

#include "PathSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/FileChecks.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/Pose.h"

namespace tetrapage {

Transform identity_transform() {
  return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
}

Transform compose_transforms(const Transform& a, const Transform& b) {
  Transform result = identity_transform();
  for (int row = 0; row < 3; ++row) {
    for (int column = 0; column < 4; ++column) {
      double sum = column == 3 ? a[4 * row + 3] : 0.0;
      for (int k = 0; k < 3; ++k) sum += a[4 * row + k] * b[4 * k + column];
      result[4 * row + column] = sum;
    }
  }
  return result;
}

double largest_stretch(const Transform& m) {
  double largest = 0;
  for (int column = 0; column < 3; ++column)
    largest = std::max(largest, std::hypot(m[column], m[4 + column], m[8 + column]));
  return largest;
}

Vec3 apply_transform(const Transform& m, const Vec3& s) {
  Vec3 p;
  for (int row = 0; row < 3; ++row)
    p[row] = (m[4 * row] * s[0] + m[4 * row + 1] * s[1] + m[4 * row + 2] * s[2]) + m[4 * row + 3];
  return p;
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
    throw FormatError(where() + what);
  }
  [[noreturn]] void input_error(const std::string& what) const { throw InputError(where() + what); }
  [[noreturn]] void io_error(const std::string& what) const { throw IoError(where() + what); }
  std::string where() const {
    return file_ + ": " + (path_.empty() ? std::string("top level") : path_) + ": ";
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
struct RepeatedKey {
  std::string key;
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

std::vector<Transform> parse_instances(const json& part, const JsonPlace& place) {
  if (!part.contains("instances")) return {identity_transform()};
  const json& instances = part["instances"];
  const JsonPlace instances_place = place.field("instances");
  if (!instances.is_array())
    instances_place.format_error("expected an array, got " + shown(instances));
  if (instances.empty())
    instances_place.format_error("empty (leave 'instances' out to place the part once)");
  std::vector<Transform> result;
  for (std::size_t k = 0; k < instances.size(); ++k)
    result.push_back(parse_instance(instances[k], instances_place[k]));
  return result;
}

json parse_document(const std::filesystem::path& path) {
  const std::string file = path.string();
  require_regular_file(path);  // a FIFO would block the read forever
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw IoError("cannot open manifest '" + file + "': " + std::strerror(errno));
  json document;
  try {
    // The callback sees each array or object open, with the number already open around it, and
    // each key: a key given twice in one object would silently keep the last value.
    std::vector<std::set<std::string>> keys_of_open_objects;
    const json::parser_callback_t check_structure = [&](int depth, json::parse_event_t event,
                                                        json& parsed) {
      if ((event == json::parse_event_t::object_start || event == json::parse_event_t::array_start) &&
          depth + 1 > kMaxJsonDepth)
        throw TooDeep{depth + 1};
      if (event == json::parse_event_t::object_start) keys_of_open_objects.emplace_back();
      if (event == json::parse_event_t::object_end) keys_of_open_objects.pop_back();
      if (event == json::parse_event_t::key &&
          !keys_of_open_objects.back().insert(parsed.get<std::string>()).second)
        throw RepeatedKey{parsed.get<std::string>()};
      return true;
    };
    // Comments are allowed, so a manifest can explain itself.
    document = json::parse(stream, check_structure, true, true);
  } catch (const TooDeep& deep) {
    throw FormatError(file + ": arrays and objects nested deeper than " + std::to_string(kMaxJsonDepth) +
                      " levels (depth " + std::to_string(deep.depth) + "); a manifest needs 6");
  } catch (const RepeatedKey& repeated) {
    throw FormatError(file + ": the key " + in_quotes(repeated.key) +
                      " is given twice in one object");
  } catch (const json::exception& error) {
    // A syntax error, or a number beyond double's range (out_of_range, found by fuzzing). Its
    // text quotes the token read last, which can be as long as the file.
    std::string what = error.what();
    if (what.size() > 200) what = what.substr(0, 197) + "...";
    throw FormatError(file + ": not valid JSON: " + what);
  }
  if (stream.bad()) throw IoError("cannot read manifest '" + file + "'");
  return document;
}

/// Sub-assemblies nest at most this many manifests deep, the top one included.
constexpr std::size_t kMaxAssemblyDepth = 64;
/// The most mesh instances an assembly may place: sub-assemblies multiply their instances, so a
/// few small manifests could otherwise ask for more placements than memory holds.
constexpr std::uint64_t kMaxPlacements = std::uint64_t(1) << 24;

/// A manifest read, and how many mesh instances it places (at most kMaxPlacements + 1).
struct ReadManifest {
  std::shared_ptr<const Manifest> manifest;
  std::uint64_t placements = 0;
};

/// The state of one read_manifest: the files open from the top down (cycles, depth), and the
/// sub-manifests read already, by canonical path (one read each, however often included).
struct ManifestReading {
  struct Open {
    std::filesystem::path key, shown;
  };
  std::vector<Open> chain;
  std::map<std::filesystem::path, ReadManifest> done;
};

std::filesystem::path file_key(const std::filesystem::path& path) {
  std::error_code error;
  const std::filesystem::path canonical = std::filesystem::weakly_canonical(path, error);
  return error ? path.lexically_normal() : canonical;
}

ReadManifest read_manifest_file(const std::filesystem::path& path, ManifestReading& reading);

/// The sub-manifest `file` named at `place`: refused when it is open already (a cycle) or one
/// too deep, read at most once.
ReadManifest read_sub_assembly(const std::filesystem::path& file, const JsonPlace& place,
                               ManifestReading& reading) {
  const std::filesystem::path key = file_key(file);
  const auto chain = [&] {
    std::string text;
    for (const auto& open : reading.chain) text += open.shown.string() + " -> ";
    return text + file.string();
  };
  for (const auto& open : reading.chain)
    if (open.key == key) place.input_error("the assembly includes itself: " + chain());
  if (reading.chain.size() >= kMaxAssemblyDepth) {
    place.input_error("sub-assemblies nested deeper than " + std::to_string(kMaxAssemblyDepth) +
                      " manifests: " + chain());
  }
  if (const auto found = reading.done.find(key); found != reading.done.end()) return found->second;
  try {
    ReadManifest sub = read_manifest_file(file, reading);
    reading.done.emplace(key, sub);
    return sub;
  } catch (const IoError& error) {
    place.io_error(error.what());
  }
}

/// Parses parts[i]; `placements` grows by the mesh instances it places (saturating).
ManifestPart parse_part(const json& part, const JsonPlace& place, const Manifest& manifest,
                        ManifestReading& reading, std::uint64_t& placements) {
  require_keys(part, place, {"name", "file", "manifest", "units", "instances"});
  const bool is_assembly = part.contains("manifest");
  if (is_assembly && part.contains("file"))
    place.format_error("give either 'file' or 'manifest', not both");
  if (!is_assembly && !part.contains("file"))
    place.format_error("missing field 'file' (or 'manifest' for a sub-assembly)");
  const char* field = is_assembly ? "manifest" : "file";
  const std::filesystem::path named = text(part[field], place.field(field));
  if (named.empty()) place.field(field).format_error("empty file name");
  if (!is_assembly && is_manifest_path(named))
    place.field("file").format_error("a manifest is included with 'manifest', not 'file'");
  if (is_assembly && part.contains("units")) {
    place.field("units").format_error("a sub-assembly's unit is its manifest's 'units'");
  }
  ManifestPart result;
  const std::filesystem::path file =
      named.is_absolute() ? named : manifest.path.parent_path() / named;
  result.name =
      part.contains("name") ? text(part["name"], place.field("name")) : named.stem().string();
  if (result.name.empty()) place.field("name").format_error("empty part name");
  if (part.contains("units")) {
    result.unit_scale =
        unit_of(part["units"], place.field("units")) / metres_per_unit(manifest.units);
    result.units_given = true;
  }
  result.instances = parse_instances(part, place);
  std::uint64_t each = 1;
  if (is_assembly) {
    const ReadManifest sub = read_sub_assembly(file, place.field("manifest"), reading);
    result.assembly = sub.manifest;
    result.unit_scale = metres_per_unit(sub.manifest->units) / metres_per_unit(manifest.units);
    each = sub.placements;
  } else {
    result.file = file;
  }
  const std::uint64_t copies = std::min<std::uint64_t>(result.instances.size(), kMaxPlacements + 1);
  placements = std::min(placements + copies * each, kMaxPlacements + 1);
  return result;
}

ReadManifest read_manifest_file(const std::filesystem::path& path, ManifestReading& reading) {
  const json document = parse_document(path);
  const std::string file = path.string();
  const JsonPlace root(file, "");
  require_keys(document, root, {"units", "parts"});
  auto manifest = std::make_shared<Manifest>();
  manifest->path = path;
  if (document.contains("units")) {
    manifest->units = text(document["units"], root.field("units"));
    unit_of(document["units"], root.field("units"));  // a known unit
  }
  if (!document.contains("parts")) root.format_error("missing field 'parts'");
  const json& parts = document["parts"];
  const JsonPlace parts_place = root.field("parts");
  if (!parts.is_array()) parts_place.format_error("expected an array, got " + shown(parts));
  if (parts.empty()) parts_place.input_error("the assembly has no part");

  reading.chain.push_back({file_key(path), path});
  std::uint64_t placements = 0;
  std::map<std::string, std::size_t> names;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const JsonPlace place = parts_place[i];
    ManifestPart part = parse_part(parts[i], place, *manifest, reading, placements);
    if (const auto [it, inserted] = names.emplace(part.name, i); !inserted) {
      place.field("name").input_error("duplicate part name " + in_quotes(part.name) +
                                      " (also parts[" + std::to_string(it->second) +
                                      "]; give each part a name)");
    }
    manifest->parts.push_back(std::move(part));
  }
  reading.chain.pop_back();
  if (placements > kMaxPlacements) {
    root.input_error("the assembly places more than " + std::to_string(kMaxPlacements) +
                     " mesh instances (sub-assemblies multiply their instances)");
  }
  return {std::move(manifest), placements};
}

/// A mesh entry of an assembly with every place the assembly puts it, computed one placement
/// at a time: 10^6 placements held whole took 180 MB of transforms and paths.
class PlacedEntry {
 public:
  /// The mesh entry `entries` of `top` (InputPiece::entries).
  PlacedEntry(const Manifest& top, std::span<const std::size_t> entries) : owner_(&top) {
    for (std::size_t level = 0; level < entries.size(); ++level) {
      if (part_ != nullptr || entries[level] >= owner_->parts.size())
        throw InputError(top.path.string() +
                         ": an input piece names no mesh entry of the manifest");
      const ManifestPart& part = owner_->parts[entries[level]];
      levels_.push_back(&part);
      count_ *= part.instances.size();
      if (part.assembly) {
        owner_ = part.assembly.get();
      } else {
        part_ = &part;
      }
    }
    if (part_ == nullptr)
      throw InputError(top.path.string() + ": an input piece names no mesh entry of the manifest");
    prefix_.assign(levels_.size(), identity_transform());
    digits_.assign(levels_.size(), kNoDigit);
  }

  const Manifest& owner() const { return *owner_; }    ///< the manifest naming the file
  const ManifestPart& part() const { return *part_; }  ///< its entry there
  std::size_t count() const { return count_; }

  /// Placement k (owner's unit -> the top manifest's unit), the outer sub-assembly's instance
  /// varying slowest. From the top down, each level's instance composes with the placement
  /// above; a sub-assembly's unit scale is folded in after its instance; a top-level entry's
  /// instance is taken as it is. Levels whose instance did not change since the last call are
  /// reused (the same operations, so the same bits).
  const Transform& transform(std::size_t k) {
    const std::vector<std::size_t> digits = digits_of(k);
    bool changed = false;
    for (std::size_t level = 0; level < levels_.size(); ++level) {
      changed = changed || digits[level] != digits_[level];
      if (!changed) continue;
      const ManifestPart& part = *levels_[level];
      Transform t = level == 0
                        ? part.instances[digits[level]]
                        : compose_transforms(prefix_[level - 1], part.instances[digits[level]]);
      if (part.assembly) {
        for (int row = 0; row < 3; ++row)
          for (int column = 0; column < 3; ++column) t[4 * row + column] *= part.unit_scale;
      }
      prefix_[level] = t;
      digits_[level] = digits[level];
    }
    return prefix_.back();
  }

  /// Placement k's instance path, "rack/board#3/U7".
  std::string path(std::size_t k) const {
    const std::vector<std::size_t> digits = digits_of(k);
    std::string path;
    for (std::size_t level = 0; level < levels_.size(); ++level) {
      const ManifestPart& part = *levels_[level];
      if (level > 0) path += '/';
      path += part.name;
      if (part.instances.size() != 1) path.append("#").append(std::to_string(digits[level]));
    }
    return path;
  }

 private:
  static constexpr std::size_t kNoDigit = std::size_t(-1);
  std::vector<std::size_t> digits_of(std::size_t k) const {
    std::vector<std::size_t> digits(levels_.size());
    for (std::size_t level = levels_.size(); level-- > 0;) {
      const std::size_t n = levels_[level]->instances.size();
      digits[level] = k % n;
      k /= n;
    }
    return digits;
  }

  const Manifest* owner_;
  const ManifestPart* part_ = nullptr;
  std::vector<const ManifestPart*> levels_;
  std::size_t count_ = 1;
  std::vector<Transform> prefix_;    ///< the last placement's transform down to each level
  std::vector<std::size_t> digits_;  ///< and its instance at each level
};

/// The mesh entries of `manifest`, depth first (InputPiece::entries each).
void mesh_entries(const Manifest& manifest, std::vector<std::size_t>& prefix,
                  std::vector<std::vector<std::size_t>>& out) {
  for (std::size_t i = 0; i < manifest.parts.size(); ++i) {
    prefix.push_back(i);
    if (manifest.parts[i].assembly) {
      mesh_entries(*manifest.parts[i].assembly, prefix, out);
    } else {
      out.push_back(prefix);
    }
    prefix.pop_back();
  }
}

/// The shortest text that reads back as `value`.
std::string number_text(double value) {
  for (int digits = 1; digits < 17; ++digits) {
    char shorter[32];
    std::snprintf(shorter, sizeof shorter, "%.*g", digits, value);
    if (std::strtod(shorter, nullptr) == value) return shorter;
  }
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

/// How far from the origin a placement may put a part, in multiples of the part's size: there
/// coordinates are spaced at most 2^-16 of the size apart (2^36 * 2^-52), so rounding keeps the
/// part's shape; beyond, it flattens the part or erases it.
constexpr double kMaxPlacementOverSize = 0x1p36;

/// Refuses a placed part whose box lies further from the origin than kMaxPlacementOverSize
/// times its size.
void check_placement_precision(const std::string& instance, const BoundingBox& box) {
  if (box.empty()) return;
  double far = 0, size = 0;
  for (int a = 0; a < 3; ++a) {
    far = std::max({far, std::fabs(box.lo[a]), std::fabs(box.hi[a])});
    size = std::max(size, box.hi[a] - box.lo[a]);
  }
  if (far <= size * kMaxPlacementOverSize) return;
  throw InputError(
      instance + ": placed " + number_text(far) + " from the origin, where coordinates are " +
      number_text(std::nextafter(far, HUGE_VAL) - far) + " apart, the part (" + number_text(size) +
      " across) loses its shape to rounding: accepted placements keep coordinates within 2^36 "
      "times the part's size");
}

/// Where placement k of `placed` puts a file's parts, and what messages call it.
struct Placement {
  Placement(PlacedEntry& placed, std::size_t k, double scale)
      : transform(placed.transform(k)), path(placed.path(k)), scale(scale) {
    const ManifestPart& part = placed.part();
    const std::string owner = placed.owner().path.string();
    instance = owner + ": part '" + part.name + "' (" + part.file.filename().string() +
               "), instance '" + path + "'";
  }
  /// A vertex of the file, placed. @throw InputError beyond the accepted coordinates.
  Vec3 place(const Vec3& v) const {
    const Vec3 p = apply_transform(transform, {v[0] * scale, v[1] * scale, v[2] * scale});
    for (int a = 0; a < 3; ++a)
      if (!(std::fabs(p[a]) <= kMaxCoordinateMagnitude))
        throw InputError(instance + ": the placement puts " + "xyz"[a] + " = " + number_text(p[a]) +
                         ", outside the accepted coordinates [-" +
                         number_text(kMaxCoordinateMagnitude) + ", " +
                         number_text(kMaxCoordinateMagnitude) + "]");
    return p;
  }
  Transform transform;
  std::string path, instance;
  double scale;
};

/// Adds the parts the placement `path` of `part` makes of a file whose parts `source` names:
/// one part per instance, or per node for a file of several parts.
void add_placed_parts(TriangleSoup& assembly, const TriangleSoup& source, const ManifestPart& part,
                      const std::string& path) {
  if (source.part_count() == 1) {
    assembly.add_part(part.name, path == part.name ? std::string() : path);
    return;
  }
  // A file of several parts (glTF nodes, named "stem/node") keeps its node names.
  const std::string stem = part.file.stem().string() + "/";
  const auto node = [&](const std::string& name) {
    return name.starts_with(stem) ? name.substr(stem.size()) : name;
  };
  for (std::size_t p = 0; p < source.part_count(); ++p)
    assembly.add_part(node(source.part_names[p]), path + "/" + node(source.part_path(p)));
}

/// Appends the parts of `source` placed by placement k of `placed`. Returns the placement's
/// largest stretch (what it scales the tessellation's deflection by).
double append_placement(TriangleSoup& assembly, const TriangleSoup& source, PlacedEntry& placed,
                        std::size_t k, double scale, std::uint64_t& degenerate_dropped) {
  const Placement placement(placed, k, scale);
  const std::string where = placed.owner().path.string() + ": part '" + placement.path + "'";
  if (assembly.vertices.size() + source.vertices.size() > std::numeric_limits<std::uint32_t>::max())
    throw InputError(where + ": the assembly has more vertices than a soup can index");
  const auto vertex_base = static_cast<std::uint32_t>(assembly.vertices.size());
  const auto part_base = static_cast<std::uint32_t>(assembly.part_count());
  add_placed_parts(assembly, source, placed.part(), placement.path);
  BoundingBox box;
  for (const Vec3& v : source.vertices) {
    assembly.vertices.push_back(placement.place(v));
    box.extend(assembly.vertices.back());
  }
  check_placement_precision(placement.instance, box);
  for (std::size_t t = 0; t < source.triangles.size(); ++t) {
    const auto& tri = source.triangles[t];
    const TriangleIndices p{tri[0] + vertex_base, tri[1] + vertex_base, tri[2] + vertex_base};
    // Rounding in the placement can flatten a sliver: drop it like the reader would.
    if (is_degenerate_triangle(assembly.vertices[p[0]], assembly.vertices[p[1]],
                               assembly.vertices[p[2]])) {
      ++degenerate_dropped;
      continue;
    }
    assembly.triangles.push_back(p);
    assembly.part_of.push_back(part_base + source.part_of[t]);
  }
  return largest_stretch(placement.transform);
}

/// Reads the file of mesh entry `entries` once and appends all its placements; a
/// tessellation's deflection is reported in the top manifest's unit.
void load_entry(TriangleSoup& assembly, const Manifest& top, std::span<const std::size_t> entries,
                std::vector<ReadReport>* reports, const TessellationOptions& tessellation) {
  // Not owned: `top` outlives the loader.
  const std::shared_ptr<const Manifest> manifest(std::shared_ptr<const Manifest>(), &top);
  const PieceLoader loader(InputPiece{top.path, manifest, {entries.begin(), entries.end()}},
                           tessellation);
  loader.place(0, loader.copies(), assembly);
  if (reports != nullptr) reports->push_back(loader.report());
}

}  // namespace

bool is_manifest_path(const std::filesystem::path& path) {
  return detail::lower_extension(path) == ".json";
}

double part_unit_scale(const ManifestPart& part, const std::string& manifest_units,
                       const std::string& file_unit) {
  if (part.units_given || file_unit.empty()) return part.unit_scale;
  double file_metres = 0;
  try {
    file_metres = metres_per_unit(file_unit);
  } catch (const InputError&) {
    throw InputError(part.file.string() + ": the file's unit " + in_quotes(file_unit) +
                     " is not one of m, cm, mm, um, in, ft; give the part 'units' in the manifest");
  }
  return file_metres / metres_per_unit(manifest_units);
}

Manifest read_manifest(const std::filesystem::path& path) {
  ManifestReading reading;
  return *read_manifest_file(path, reading).manifest;
}

TriangleSoup load_assembly(const Manifest& manifest, std::vector<ReadReport>* reports,
                           Progress& progress, const TessellationOptions& tessellation) {
  std::vector<std::vector<std::size_t>> entries;
  std::vector<std::size_t> prefix;
  mesh_entries(manifest, prefix, entries);
  TriangleSoup assembly;
  for (const auto& entry : entries) {
    load_entry(assembly, manifest, entry, reports, tessellation);
    progress.advance(1);
  }
  return assembly;
}

const std::filesystem::path& InputPiece::file() const {
  if (!manifest) return input;
  const Manifest* owner = manifest.get();
  for (std::size_t level = 0; level + 1 < entries.size(); ++level)
    owner = owner->parts.at(entries[level]).assembly.get();
  return owner->parts.at(entries.at(entries.size() - 1)).file;
}

std::size_t InputPiece::copies() const {
  if (!manifest) return 1;
  std::size_t copies = 1;
  const Manifest* owner = manifest.get();
  for (const std::size_t entry : entries) {
    copies *= owner->parts.at(entry).instances.size();
    owner = owner->parts[entry].assembly.get();
  }
  return copies;
}

std::vector<InputPiece> input_pieces(const std::vector<std::filesystem::path>& inputs) {
  std::vector<InputPiece> pieces;
  for (const auto& input : inputs) {
    if (!is_manifest_path(input)) {
      pieces.push_back({input, nullptr, {}});
      continue;
    }
    const auto manifest = std::make_shared<const Manifest>(read_manifest(input));
    std::vector<std::vector<std::size_t>> entries;
    std::vector<std::size_t> prefix;
    mesh_entries(*manifest, prefix, entries);
    for (auto& entry : entries) pieces.push_back({input, manifest, std::move(entry)});
  }
  return pieces;
}

struct PieceLoader::Impl {
  InputPiece piece;
  ReadReport report;
  TriangleSoup source;
  double scale = 1;  ///< the file's unit -> its manifest's
  std::size_t copies = 1;
  std::atomic<std::uint64_t> dropped{0};  ///< by the placements
  mutable std::mutex stretch_mutex;
  double stretch = 0;  ///< the largest of the placements so far
};

namespace {

// The piece's file read as read_mesh reads it (a bad entry refused before the read).
std::pair<TriangleSoup, ReadReport> read_piece_file(const InputPiece& piece,
                                                    const TessellationOptions& tessellation) {
  std::pair<TriangleSoup, ReadReport> read;
  const std::filesystem::path file =
      piece.manifest ? PlacedEntry(*piece.manifest, piece.entries).part().file : piece.input;
  read.first = read_mesh(file, &read.second, tessellation);
  return read;
}

}  // namespace

PieceLoader::PieceLoader(const InputPiece& piece, const TessellationOptions& tessellation)
    : PieceLoader(piece, read_piece_file(piece, tessellation)) {}

PieceLoader::PieceLoader(const InputPiece& piece, std::pair<TriangleSoup, ReadReport> read)
    : PieceLoader(piece, std::move(read.first), read.second) {}

PieceLoader::PieceLoader(const InputPiece& piece, TriangleSoup source, const ReadReport& report)
    : impl_(std::make_unique<Impl>()) {
  impl_->piece = piece;
  impl_->report = report;
  impl_->source = std::move(source);
  if (!piece.manifest) return;
  const PlacedEntry placed(*piece.manifest, piece.entries);
  impl_->copies = placed.count();
  impl_->scale = part_unit_scale(placed.part(), placed.owner().units, report.length_unit);
}

PieceLoader::~PieceLoader() = default;
PieceLoader::PieceLoader(PieceLoader&&) noexcept = default;
PieceLoader& PieceLoader::operator=(PieceLoader&&) noexcept = default;

std::size_t PieceLoader::copies() const {
  return impl_->copies;
}
const TriangleSoup& PieceLoader::source() const {
  return impl_->source;
}
bool PieceLoader::placed_as_read() const {
  return !impl_->piece.manifest;
}

void PieceLoader::place(std::size_t first, std::size_t count, TriangleSoup& soup) const {
  if (!impl_->piece.manifest) {
    if (first == 0 && count == 1) soup.append(impl_->source);
    return;
  }
  // A placement cache of its own: batches may be placed on several threads at once.
  PlacedEntry placed(*impl_->piece.manifest, impl_->piece.entries);
  // Sized once: grown copy by copy, the arrays would hold up to twice the copies.
  const TriangleSoup& source = impl_->source;
  const std::size_t placing = std::min(count, impl_->copies - std::min(first, impl_->copies));
  soup.vertices.reserve(soup.vertices.size() + placing * source.vertices.size());
  soup.triangles.reserve(soup.triangles.size() + placing * source.triangles.size());
  soup.part_of.reserve(soup.part_of.size() + placing * source.triangles.size());
  std::uint64_t dropped = 0;
  double stretch = 0;
  for (std::size_t k = first; k < first + count && k < impl_->copies; ++k) {
    stretch = std::max(stretch, append_placement(soup, impl_->source, placed, k, impl_->scale, dropped));
  }
  impl_->dropped += dropped;
  const std::lock_guard lock(impl_->stretch_mutex);
  impl_->stretch = std::max(impl_->stretch, stretch);
}

TriangleSoup PieceLoader::take_source() {
  return std::move(impl_->source);
}

ReadReport PieceLoader::report() const {
  ReadReport report = impl_->report;
  report.degenerate_dropped += impl_->dropped;
  if (impl_->piece.manifest) {
    const std::lock_guard lock(impl_->stretch_mutex);
    report.tessellation_deflection *= impl_->scale * impl_->stretch;
  }
  return report;
}

struct PlacedChunks::Impl {
  Impl(const InputPiece& piece, std::size_t copy, const std::string& file_unit)
      : placed(*piece.manifest, piece.entries),
        scale(part_unit_scale(placed.part(), placed.owner().units, file_unit)),
        placement(placed, copy, scale) {}
  PlacedEntry placed;
  double scale;
  Placement placement;
  BoundingBox box;
  std::uint64_t dropped = 0;
};

PlacedChunks::PlacedChunks(const InputPiece& piece, std::size_t copy, const std::string& file_unit) {
  if (!piece.manifest || copy >= piece.copies())
    throw InputError(piece.input.string() + ": no placement " + std::to_string(copy) + " to place");
  impl_ = std::make_unique<Impl>(piece, copy, file_unit);
}
PlacedChunks::~PlacedChunks() = default;

void PlacedChunks::note_vertex(const Vec3& vertex) {
  impl_->box.extend(impl_->placement.place(vertex));
}

void PlacedChunks::place(TriangleSoup& chunk) {
  for (Vec3& v : chunk.vertices) v = impl_->placement.place(v);
  std::size_t kept = 0;
  for (std::size_t t = 0; t < chunk.triangle_count(); ++t) {
    const auto& c = chunk.triangles[t];
    if (is_degenerate_triangle(chunk.vertices[c[0]], chunk.vertices[c[1]], chunk.vertices[c[2]])) {
      ++impl_->dropped;
      continue;
    }
    chunk.triangles[kept] = c;
    chunk.part_of[kept++] = chunk.part_of[t];
  }
  chunk.triangles.resize(kept);
  chunk.part_of.resize(kept);
}

TriangleSoup PlacedChunks::finish(const TriangleSoup& file_parts) {
  check_placement_precision(impl_->placement.instance, impl_->box);
  TriangleSoup parts;
  add_placed_parts(parts, file_parts, impl_->placed.part(), impl_->placement.path);
  return parts;
}

std::uint64_t PlacedChunks::dropped() const { return impl_->dropped; }

double PlacedChunks::largest_scale() const {
  return impl_->scale * largest_stretch(impl_->placement.transform);
}

TriangleSoup load_input_piece(const InputPiece& piece, std::vector<ReadReport>* reports,
                              const TessellationOptions& tessellation) {
  PieceLoader loader(piece, tessellation);
  TriangleSoup soup;
  if (loader.placed_as_read()) {
    soup = loader.take_source();
  } else {
    loader.place(0, loader.copies(), soup);
  }
  if (reports != nullptr) reports->push_back(loader.report());
  return soup;
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
