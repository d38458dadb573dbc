// PLY (ascii, binary_little_endian, binary_big_endian). From the "vertex" element we keep the
// scalar properties x, y, z (any PLY scalar type); from the "face" element the list property
// "vertex_indices" (or "vertex_index"), with any count and index types; from a "part" element
// (our writer's part table, MeshWriter.h) the integer "faces" and the byte lists "name" and
// "path". Every other element and property is skipped by walking its declared layout, so it
// cannot desynchronise the read.

#include <type_traits>
#include <vector>

#include "ReaderSupport.h"

namespace tetrapage::detail {
namespace {

enum class PlyType { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

std::size_t size_of(PlyType type) {
  switch (type) {
    case PlyType::int8:
    case PlyType::uint8:
      return 1;
    case PlyType::int16:
    case PlyType::uint16:
      return 2;
    case PlyType::int32:
    case PlyType::uint32:
    case PlyType::float32:
      return 4;
    case PlyType::float64:
      return 8;
  }
  return 0;
}

bool is_integer(PlyType type) {
  return type != PlyType::float32 && type != PlyType::float64;
}

bool parse_type(std::string_view name, PlyType& type) {
  struct Named {
    std::string_view name;
    PlyType type;
  };
  static constexpr Named names[] = {
      {"char", PlyType::int8},      {"int8", PlyType::int8},       {"uchar", PlyType::uint8},
      {"uint8", PlyType::uint8},    {"short", PlyType::int16},     {"int16", PlyType::int16},
      {"ushort", PlyType::uint16},  {"uint16", PlyType::uint16},   {"int", PlyType::int32},
      {"int32", PlyType::int32},    {"uint", PlyType::uint32},     {"uint32", PlyType::uint32},
      {"float", PlyType::float32},  {"float32", PlyType::float32}, {"double", PlyType::float64},
      {"float64", PlyType::float64}};
  for (const auto& named : names) {
    if (named.name == name) {
      type = named.type;
      return true;
    }
  }
  return false;
}

// One stored value of any PLY type as Result. Integers are only asked of integer types (the
// header check guarantees it for counts and indices), so no float is ever truncated.
template <class Result>
Result load_number(PlyType type, const char* bytes, bool big_endian) {
  switch (type) {
    case PlyType::int8:
      return Result(load_scalar<std::int8_t>(bytes, big_endian));
    case PlyType::uint8:
      return Result(load_scalar<std::uint8_t>(bytes, big_endian));
    case PlyType::int16:
      return Result(load_scalar<std::int16_t>(bytes, big_endian));
    case PlyType::uint16:
      return Result(load_scalar<std::uint16_t>(bytes, big_endian));
    case PlyType::int32:
      return Result(load_scalar<std::int32_t>(bytes, big_endian));
    case PlyType::uint32:
      return Result(load_scalar<std::uint32_t>(bytes, big_endian));
    case PlyType::float32:
      return std::is_floating_point_v<Result> ? Result(load_scalar<float>(bytes, big_endian)) : Result(0);
    case PlyType::float64:
      return std::is_floating_point_v<Result> ? Result(load_scalar<double>(bytes, big_endian)) : Result(0);
  }
  return Result(0);
}

double load_double(PlyType type, const char* bytes, bool big_endian) {
  return load_number<double>(type, bytes, big_endian);
}

std::int64_t load_integer(PlyType type, const char* bytes, bool big_endian) {
  return load_number<std::int64_t>(type, bytes, big_endian);
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::float32;  ///< the item type for a list
  bool is_list = false;
  PlyType count_type = PlyType::uint8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  /// The fewest bytes a record can take: binary, each scalar and each list's count (an empty
  /// list); ASCII, a token and a separator per property.
  std::uint64_t minimal_size(bool ascii) const {
    std::uint64_t size = 0;
    for (const auto& property : properties)
      size += ascii ? 2 : size_of(property.is_list ? property.count_type : property.type);
    return size;
  }
  /// Bytes per record when no property is a list, else 0.
  std::size_t fixed_size() const {
    std::size_t size = 0;
    for (const auto& property : properties) {
      if (property.is_list) return 0;
      size += size_of(property.type);
    }
    return size;
  }
};

enum class PlyEncoding { ascii, binary_little_endian, binary_big_endian };

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::ascii;
  std::vector<PlyElement> elements;
};

PlyHeader read_header(InputFile& file) {
  std::string_view line;
  if (!file.next_line(line) || line != "ply") {
    throw FormatError(file.name() + ": not a PLY file (the first line is not 'ply')");
  }
  PlyHeader header;
  bool have_format = false;
  for (;;) {
    if (!file.next_line(line)) throw FormatError(file.name() + ": the header has no 'end_header'");
    std::string_view rest = line;
    const std::string_view keyword = next_token(rest);
    if (keyword == "end_header") break;
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      const std::string_view encoding = next_token(rest);
      if (encoding == "ascii") {
        header.encoding = PlyEncoding::ascii;
      } else if (encoding == "binary_little_endian") {
        header.encoding = PlyEncoding::binary_little_endian;
      } else if (encoding == "binary_big_endian") {
        header.encoding = PlyEncoding::binary_big_endian;
      } else {
        throw FormatError(where_line(file) + "unknown PLY format " + quote_token(encoding));
      }
      have_format = true;
    } else if (keyword == "element") {
      PlyElement element;
      element.name = std::string(next_token(rest));
      const std::string_view count = next_token(rest);
      if (element.name.empty() || !parse_unsigned(count, element.count)) {
        throw FormatError(where_line(file) + "malformed element line " + quote_token(line));
      }
      header.elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (header.elements.empty()) {
        throw FormatError(where_line(file) + "property before any element");
      }
      PlyProperty property;
      std::string_view type = next_token(rest);
      if (type == "list") {
        property.is_list = true;
        const std::string_view count_type = next_token(rest);
        if (!parse_type(count_type, property.count_type) || !is_integer(property.count_type)) {
          throw FormatError(where_line(file) + "bad list count type " + quote_token(count_type));
        }
        type = next_token(rest);
      }
      if (!parse_type(type, property.type)) {
        throw FormatError(where_line(file) + "unknown property type " + quote_token(type));
      }
      property.name = std::string(next_token(rest));
      if (property.name.empty()) {
        throw FormatError(where_line(file) + "malformed property line " + quote_token(line));
      }
      header.elements.back().properties.push_back(std::move(property));
    } else {
      throw FormatError(where_line(file) + "unknown header keyword " + quote_token(keyword));
    }
  }
  if (!have_format) throw FormatError(file.name() + ": the header has no 'format' line");
  return header;
}

/// Every element's announced records must fit in what follows the header, each at its minimal
/// size, before anything is sized by a count (a 300-byte file may announce 2^32 faces).
void check_counts_fit(const InputFile& file, const PlyHeader& header) {
  const bool ascii = header.encoding == PlyEncoding::ascii;
  // ASCII: the last token of the file needs no separator.
  const std::uint64_t available = file.bytes_left() + (ascii ? 1 : 0);
  std::uint64_t needed = 0;
  for (const auto& element : header.elements) {
    const std::uint64_t record = element.minimal_size(ascii);
    if (record == 0 || element.count == 0) continue;
    if (element.count > (available - needed) / record)
      throw FormatError(file.name() + ": element '" + element.name + "' announces " +
                        std::to_string(element.count) + " records of at least " +
                        std::to_string(record) + " bytes, but only " + std::to_string(file.bytes_left()) +
                        " bytes follow the header" + (needed > 0 ? " and the elements before it" : ""));
    needed += element.count * record;
  }
}

/// Where x, y, z, the face corners and the part table sit in their elements.
struct PlyLayout {
  const PlyElement* vertex = nullptr;
  int coordinate[3] = {-1, -1, -1};  ///< property index of x, y, z
  const PlyElement* face = nullptr;
  int corners = -1;  ///< property index of vertex_indices
  const PlyElement* parts = nullptr;                    ///< the part table, when there is one
  int part_faces = -1, part_name = -1, part_path = -1;  ///< its property indices (path: -1 if none)
};

// Our writer's part table: an element "part" with an integer "faces" and lists of bytes
// "name" (and "path"). Anything else named "part" is some other tool's and skipped.
void find_part_table(const PlyHeader& header, PlyLayout& layout) {
  for (const auto& element : header.elements) {
    if (element.name != "part") continue;
    int faces = -1, name = -1, path = -1;
    for (std::size_t p = 0; p < element.properties.size(); ++p) {
      const auto& property = element.properties[p];
      const bool bytes = property.is_list && size_of(property.type) == 1;
      if (property.name == "faces" && !property.is_list && is_integer(property.type))
        faces = int(p);
      if (property.name == "name" && bytes) name = int(p);
      if (property.name == "path" && bytes) path = int(p);
    }
    if (faces < 0 || name < 0) return;
    layout.parts = &element;
    layout.part_faces = faces;
    layout.part_name = name;
    layout.part_path = path;
    return;
  }
}

// The part table's parts, made in the soup as its records are read. The table follows the
// faces (Assimp 5.2 fails on an element before them), so the triangles get their parts at
// the end: part k holds the next faces[k] faces, and a face of n corners made n - 2
// triangles, hence the polygons are noted as the faces go by.
class PlyPartTable {
 public:
  PlyPartTable(const InputFile& file, SoupBuilder& soup, bool present)
      : file_(file), soup_(soup), present_(present) {}

  void add(std::uint64_t faces, std::string name, std::string path) {
    if (name.empty()) name = file_.path().stem().string();
    ids_.push_back(soup_.begin_part(std::move(name), std::move(path)));
    faces_.push_back(faces);
  }
  void note_face(std::uint64_t face, std::int64_t corners) {
    if (known_) {
      while (face >= part_end_ && next_ < ids_.size()) part_end_ += faces_[next_++];
      soup_.resume_part(ids_[next_ - 1]);
      return;
    }
    if (present_ && corners > 3) polygons_.push_back({face, std::uint64_t(corners - 3)});
  }
  /// The table was read up front (apply() called): the faces get their parts as they are read,
  /// and the table met again is skipped.
  void know_parts() {
    known_ = !ids_.empty();
    next_ = 0;
    part_end_ = 0;
  }
  bool known() const { return known_; }
  /// After every element: the table checked, then each triangle given its part.
  void apply(std::uint64_t face_count) {
    if (!present_) return;
    check(face_count);
    std::uint64_t face = 0, triangle = 0;
    auto polygon = polygons_.begin();
    for (std::size_t k = 0; k < ids_.size(); ++k) {
      std::uint64_t triangles = faces_[k];
      for (face += faces_[k]; polygon != polygons_.end() && polygon->first < face; ++polygon)
        triangles += polygon->second;
      soup_.assign_part(triangle, triangle + triangles, ids_[k]);
      triangle += triangles;
    }
  }
  /// The table's counts must add up to the face element's.
  /// @throw FormatError naming both counts when they differ.
  void check(std::uint64_t face_count) const {
    std::uint64_t counted = 0;  // stops past face_count: a file's counts may overflow a sum
    for (const auto faces : faces_) counted += std::min(faces, face_count + 1 - counted);
    if (counted != face_count)
      throw FormatError(file_.name() + ": the part table counts " +
                        (counted > face_count ? "more" : std::to_string(counted)) +
                        " faces, the face element has " + std::to_string(face_count));
  }

 private:
  const InputFile& file_;
  SoupBuilder& soup_;
  bool present_;
  std::vector<std::uint32_t> ids_;
  std::vector<std::uint64_t> faces_;                               ///< per part
  std::vector<std::pair<std::uint64_t, std::uint64_t>> polygons_;  ///< (face, corners - 3)
  bool known_ = false;
  std::size_t next_ = 0;        ///< known: the part after the current face's
  std::uint64_t part_end_ = 0;  ///< known: the face that ends the current part
};

// What a pass over a PLY file reads of its vertices, faces and part table: everything; the part
// table alone (before the faces, when the faces go out in chunks and need their parts as they
// are read); the vertices alone (before the faces, when they come after them and the faces go
// out in chunks); the rest.
struct PlyPass {
  bool vertices = true, faces = true, table = true;
};
constexpr PlyPass kWholePass{}, kTablePass{false, false, true}, kVerticesPass{true, false, false};

PlyLayout find_layout(const InputFile& file, const PlyHeader& header) {
  PlyLayout layout;
  for (const auto& element : header.elements) {
    if (element.name == "vertex" && layout.vertex == nullptr) layout.vertex = &element;
    if (element.name == "face" && layout.face == nullptr) layout.face = &element;
  }
  if (layout.vertex == nullptr) throw FormatError(file.name() + ": no 'vertex' element");
  for (std::size_t p = 0; p < layout.vertex->properties.size(); ++p) {
    const auto& property = layout.vertex->properties[p];
    static constexpr std::string_view axis_names[3] = {"x", "y", "z"};
    for (int axis = 0; axis < 3; ++axis) {
      if (property.name == axis_names[axis] && layout.coordinate[axis] < 0) {
        if (property.is_list) {
          throw FormatError(file.name() + ": vertex property '" + property.name +
                            "' is a list, expected a scalar");
        }
        layout.coordinate[axis] = static_cast<int>(p);
      }
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    if (layout.coordinate[axis] < 0) {
      throw FormatError(file.name() + ": the vertex element has no property '" +
                        std::string(1, "xyz"[axis]) + "'");
    }
  }
  if (layout.vertex->count > max_vertices) {
    throw InputError(file.name() + ": " + std::to_string(layout.vertex->count) +
                     " vertices are more than a soup can index");
  }
  if (layout.face != nullptr) {
    for (std::size_t p = 0; p < layout.face->properties.size(); ++p) {
      const auto& property = layout.face->properties[p];
      if ((property.name == "vertex_indices" || property.name == "vertex_index") &&
          layout.corners < 0) {
        if (!property.is_list || !is_integer(property.type)) {
          throw FormatError(file.name() + ": face property '" + property.name +
                            "' must be a list of integers");
        }
        layout.corners = static_cast<int>(p);
      }
    }
    if (layout.corners < 0) {
      throw FormatError(file.name() + ": the face element has no list 'vertex_indices'");
    }
  }
  find_part_table(header, layout);
  return layout;
}

class BinaryPlyReader {
 public:
  BinaryPlyReader(InputFile& file, bool big_endian, SoupBuilder& soup, const PlyLayout& layout,
                  PlyPartTable& parts, PlyPass pass = kWholePass)
      : file_(file), big_endian_(big_endian), soup_(soup), layout_(layout), parts_(parts),
        pass_(pass) {}

  void read_element(const PlyElement& element) {
    if (&element == layout_.vertex && pass_.vertices) {
      read_vertices(element);
    } else if (&element == layout_.face && pass_.faces) {
      read_faces(element);
    } else if (&element == layout_.parts && pass_.table) {
      read_parts(element);
    } else {
      skip(element);
    }
  }

 private:
  std::span<const char> take(std::size_t bytes, const PlyElement& element, std::uint64_t index) {
    const auto data = file_.take(bytes);
    if (data.size() < bytes) {
      throw FormatError(where_element(file_, element.name, index) + "truncated: needs " +
                        std::to_string(bytes) + " bytes at byte " +
                        std::to_string(file_.offset() - data.size()) + ", the file has " +
                        std::to_string(file_.size()) + " bytes (element '" + element.name +
                        "' announces " + std::to_string(element.count) + " records)");
    }
    return data;
  }

  /// Reads one list's count and returns its items' bytes.
  std::span<const char> take_list(const PlyProperty& property, const PlyElement& element,
                                  std::uint64_t index, std::int64_t& count) {
    count = load_integer(property.count_type,
                         take(size_of(property.count_type), element, index).data(), big_endian_);
    if (count < 0) {
      throw FormatError(where_element(file_, element.name, index) + "negative list count " +
                        std::to_string(count) + " for '" + property.name + "'");
    }
    const std::size_t item_size = size_of(property.type);
    if (static_cast<std::uint64_t>(count) > file_.bytes_left() / item_size)
      throw FormatError(where_element(file_, element.name, index) + "truncated: list '" + property.name +
                        "' announces " + std::to_string(count) + " items of " + std::to_string(item_size) +
                        " bytes, which needs more than the " + std::to_string(file_.bytes_left()) +
                        " bytes left");
    return take(static_cast<std::size_t>(count) * item_size, element, index);
  }

  void read_vertices(const PlyElement& element) {
    const std::size_t record_size = element.fixed_size();
    std::size_t offset[3] = {0, 0, 0};
    PlyType type[3];
    for (int axis = 0; axis < 3; ++axis) {
      type[axis] = element.properties[layout_.coordinate[axis]].type;
      for (int p = 0; p < layout_.coordinate[axis]; ++p)
        offset[axis] += size_of(element.properties[p].type);
    }
    for (std::uint64_t v = 0; v < element.count; ++v) {
      Vec3 point{};
      if (record_size > 0) {
        const char* record = take(record_size, element, v).data();
        for (int axis = 0; axis < 3; ++axis)
          point[axis] = load_double(type[axis], record + offset[axis], big_endian_);
      } else {
        for (std::size_t p = 0; p < element.properties.size(); ++p) {
          const auto& property = element.properties[p];
          std::int64_t count = 0;
          if (property.is_list) {
            take_list(property, element, v, count);
            continue;
          }
          const char* bytes = take(size_of(property.type), element, v).data();
          for (int axis = 0; axis < 3; ++axis) {
            if (static_cast<int>(p) == layout_.coordinate[axis])
              point[axis] = load_double(property.type, bytes, big_endian_);
          }
        }
      }
      if (!is_finite(point)) throw_not_finite(where_element(file_, "vertex", v), point);
      soup_.add_vertex(point);
    }
  }

  void read_parts(const PlyElement& element) {
    for (std::uint64_t r = 0; r < element.count; ++r) {
      std::uint64_t faces = 0;
      std::string name, path;
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const auto& property = element.properties[p];
        const int index = static_cast<int>(p);
        if (!property.is_list) {
          const char* bytes = take(size_of(property.type), element, r).data();
          if (index == layout_.part_faces) faces = read_face_count(property, bytes, r);
          continue;
        }
        std::int64_t count = 0;
        const auto items = take_list(property, element, r, count);
        if (index == layout_.part_name) name.assign(items.data(), items.size());
        if (index == layout_.part_path) path.assign(items.data(), items.size());
      }
      parts_.add(faces, std::move(name), std::move(path));
    }
  }

  std::uint64_t read_face_count(const PlyProperty& property, const char* bytes, std::uint64_t r) {
    const std::int64_t faces = load_integer(property.type, bytes, big_endian_);
    if (faces < 0)
      throw FormatError(where_element(file_, "part", r) + "negative face count " +
                        std::to_string(faces));
    return static_cast<std::uint64_t>(faces);
  }

  void read_faces(const PlyElement& element) {
    const std::uint64_t vertex_count = layout_.vertex->count;
    for (std::uint64_t f = 0; f < element.count; ++f) {
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const auto& property = element.properties[p];
        if (!property.is_list) {
          take(size_of(property.type), element, f);
          continue;
        }
        std::int64_t count = 0;
        const char* items = take_list(property, element, f, count).data();
        if (static_cast<int>(p) != layout_.corners) continue;
        if (count < 3) {
          throw FormatError(where_element(file_, "face", f) + "face has " + std::to_string(count) +
                            " corners, a face needs at least 3");
        }
        parts_.note_face(f, count);
        corners_.clear();
        const std::size_t item_size = size_of(property.type);
        for (std::int64_t k = 0; k < count; ++k) {
          const std::int64_t index =
              load_integer(property.type, items + k * item_size, big_endian_);
          if (index < 0 || static_cast<std::uint64_t>(index) >= vertex_count) {
            throw InputError(where_element(file_, "face", f) + "vertex index " +
                             std::to_string(index) + " out of range (" +
                             std::to_string(vertex_count) + " vertices)");
          }
          corners_.push_back(static_cast<std::uint32_t>(index));
        }
        soup_.add_polygon(corners_);
      }
    }
  }

  void skip(const PlyElement& element) {
    if (element.properties.empty()) return;  // records of nothing, however many
    const std::size_t record_size = element.fixed_size();
    if (record_size > 0) {
      // Skip in blocks rather than record by record; report the first record that is missing.
      std::uint64_t remaining = element.count;
      std::uint64_t index = 0;
      const std::uint64_t block = std::max<std::uint64_t>(1, (1u << 20) / record_size);
      while (remaining > 0) {
        const std::uint64_t records = std::min(remaining, block);
        const auto data = file_.take(static_cast<std::size_t>(records * record_size));
        if (data.size() < records * record_size) {
          index += data.size() / record_size;
          throw FormatError(where_element(file_, element.name, index) + "truncated: needs " +
                            std::to_string(record_size * (element.count - index)) +
                            " more bytes, the file has " + std::to_string(file_.size()) + " bytes");
        }
        remaining -= records;
        index += records;
      }
      return;
    }
    for (std::uint64_t r = 0; r < element.count; ++r) {
      for (const auto& property : element.properties) {
        std::int64_t count = 0;
        if (property.is_list) {
          take_list(property, element, r, count);
        } else {
          take(size_of(property.type), element, r);
        }
      }
    }
  }

  InputFile& file_;
  bool big_endian_;
  SoupBuilder& soup_;
  const PlyLayout& layout_;
  PlyPartTable& parts_;
  PlyPass pass_;
  std::vector<std::uint32_t> corners_;
};

class AsciiPlyReader {
 public:
  AsciiPlyReader(InputFile& file, SoupBuilder& soup, const PlyLayout& layout, PlyPartTable& parts,
                 PlyPass pass = kWholePass)
      : file_(file), tokens_(file), soup_(soup), layout_(layout), parts_(parts), pass_(pass) {}

  void read_element(const PlyElement& element) {
    if (&element == layout_.parts && pass_.table) return read_parts(element);
    if (element.properties.empty()) return;  // records of nothing, however many
    // Elements not read are tokenised all the same, record by record (an ASCII file has no
    // other way past them).
    const bool is_vertex = pass_.vertices && &element == layout_.vertex;
    const bool is_face = pass_.faces && &element == layout_.face;
    for (std::uint64_t r = 0; r < element.count; ++r) {
      Vec3 point{};
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const auto& property = element.properties[p];
        const int index = static_cast<int>(p);
        if (property.is_list) {
          const std::int64_t count = parse_count(property, element, r);
          if (is_face && index == layout_.corners) {
            read_corners(count, r);
          } else {
            for (std::int64_t k = 0; k < count; ++k) value_token(property, element, r);
          }
          continue;
        }
        const std::string_view token = value_token(property, element, r);
        if (!is_vertex) continue;
        for (int axis = 0; axis < 3; ++axis) {
          if (index == layout_.coordinate[axis] && !parse_double(token, point[axis])) {
            throw FormatError(where_line(file_) + "vertex " + std::to_string(r) +
                              ": expected a number for '" + property.name + "', got " +
                              quote_token(token));
          }
        }
      }
      if (is_vertex) {
        if (!is_finite(point)) {
          throw_not_finite(where_line(file_) + "vertex " + std::to_string(r) + ": ", point);
        }
        soup_.add_vertex(point);
      }
    }
  }

 private:
  std::string_view value_token(const PlyProperty& property, const PlyElement& element,
                               std::uint64_t r) {
    const std::string_view token = tokens_.next();
    if (token.empty()) {
      throw FormatError(file_.name() + ": the file ends inside element '" + element.name + "' " +
                        std::to_string(r) + " (property '" + property.name + "'; the header " +
                        "announces " + std::to_string(element.count) + " records)");
    }
    return token;
  }

  void read_parts(const PlyElement& element) {
    for (std::uint64_t r = 0; r < element.count; ++r) {
      std::int64_t faces = 0;
      std::string name, path;
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const auto& property = element.properties[p];
        const int index = static_cast<int>(p);
        if (!property.is_list) {
          const std::string_view token = value_token(property, element, r);
          if (index == layout_.part_faces && (!parse_integer(token, faces) || faces < 0))
            throw FormatError(where_line(file_) + "part " + std::to_string(r) +
                              ": bad face count " + quote_token(token));
          continue;
        }
        const std::int64_t count = parse_count(property, element, r);
        std::string* text = index == layout_.part_name   ? &name
                            : index == layout_.part_path ? &path
                                                         : nullptr;
        for (std::int64_t k = 0; k < count; ++k) {
          const std::string_view token = value_token(property, element, r);
          std::int64_t byte = 0;
          if (text != nullptr && (!parse_integer(token, byte) || byte < -128 || byte > 255))
            throw FormatError(where_line(file_) + "part " + std::to_string(r) + ": bad byte " +
                              quote_token(token) + " in '" + property.name + "'");
          if (text != nullptr) text->push_back(static_cast<char>(byte));
        }
      }
      parts_.add(static_cast<std::uint64_t>(faces), std::move(name), std::move(path));
    }
  }

  std::int64_t parse_count(const PlyProperty& property, const PlyElement& element,
                           std::uint64_t r) {
    const std::string_view token = value_token(property, element, r);
    std::int64_t count = 0;
    if (!parse_integer(token, count) || count < 0) {
      throw FormatError(where_line(file_) + element.name + " " + std::to_string(r) +
                        ": bad list count " + quote_token(token) + " for '" + property.name + "'");
    }
    // Each item is a token and a separator (the file's last one needs none).
    if (static_cast<std::uint64_t>(count) > tokens_.bytes_left() / 2 + 1)
      throw FormatError(where_line(file_) + element.name + " " + std::to_string(r) + ": list '" +
                        property.name + "' announces " + std::to_string(count) + " items, but only " +
                        std::to_string(tokens_.bytes_left()) + " bytes are left");
    return count;
  }

  void read_corners(std::int64_t count, std::uint64_t r) {
    const auto& property = layout_.face->properties[layout_.corners];
    if (count < 3) {
      throw FormatError(where_line(file_) + "face " + std::to_string(r) + ": face has " +
                        std::to_string(count) + " corners, a face needs at least 3");
    }
    parts_.note_face(r, count);
    corners_.clear();
    const std::uint64_t vertex_count = layout_.vertex->count;
    for (std::int64_t k = 0; k < count; ++k) {
      const std::string_view token = value_token(property, *layout_.face, r);
      std::int64_t index = 0;
      if (!parse_integer(token, index)) {
        throw FormatError(where_line(file_) + "face " + std::to_string(r) +
                          ": expected a vertex index, got " + quote_token(token));
      }
      if (index < 0 || static_cast<std::uint64_t>(index) >= vertex_count) {
        throw InputError(where_line(file_) + "face " + std::to_string(r) + ": vertex index " +
                         std::to_string(index) + " out of range (" + std::to_string(vertex_count) +
                         " vertices)");
      }
      corners_.push_back(static_cast<std::uint32_t>(index));
    }
    soup_.add_polygon(corners_);
  }

  InputFile& file_;
  TokenReader tokens_;
  SoupBuilder& soup_;
  const PlyLayout& layout_;
  PlyPartTable& parts_;
  PlyPass pass_;
  std::vector<std::uint32_t> corners_;
};

}  // namespace

namespace {

// The vertex element comes before the faces (the layout's elements point into the header's,
// in file order).
bool vertices_first(const PlyLayout& layout) {
  return layout.face == nullptr || layout.vertex < layout.face;
}

}  // namespace

MeshCounts read_ply_counts(InputFile& file) {
  const PlyHeader header = read_header(file);
  const PlyLayout layout = find_layout(file, header);
  check_counts_fit(file, header);
  MeshCounts counts;
  counts.vertices = layout.vertex->count;
  counts.faces = layout.face != nullptr ? layout.face->count : 0;
  counts.triangles = counts.faces;
  if (header.encoding == PlyEncoding::ascii || counts.faces == 0) return counts;
  // Binary: the bytes after the fixed-size elements before the faces bound the faces' corners,
  // hence their triangles (a face of k corners makes k - 2; polygons make more than a face).
  std::uint64_t before = 0;
  for (const auto& element : header.elements) {
    if (&element == layout.face) break;
    if (element.fixed_size() == 0) return counts;
    before += element.count * element.fixed_size();
  }
  const PlyProperty& list = layout.face->properties[std::size_t(layout.corners)];
  const std::uint64_t per_face = layout.face->minimal_size(false);
  const std::uint64_t faces_bytes = file.bytes_left() - std::min(file.bytes_left(), before);
  if (faces_bytes / counts.faces < per_face) return counts;
  const std::uint64_t corners = (faces_bytes - counts.faces * per_face) / size_of(list.type);
  if (corners > 2 * counts.faces) counts.triangles = std::max(counts.faces, corners - 2 * counts.faces);
  return counts;
}

namespace {

// Reads the elements of `header` from `file` as `pass` says.
void read_elements(InputFile& file, const PlyHeader& header, const PlyLayout& layout,
                   SoupBuilder& soup, PlyPartTable& parts, PlyPass pass) {
  if (header.encoding == PlyEncoding::ascii) {
    AsciiPlyReader reader(file, soup, layout, parts, pass);
    for (const auto& element : header.elements) reader.read_element(element);
  } else {
    BinaryPlyReader reader(file, header.encoding == PlyEncoding::binary_big_endian, soup, layout,
                           parts, pass);
    for (const auto& element : header.elements) reader.read_element(element);
  }
}

// Reads the elements `pass` names in a pass of its own over the file (a second InputFile):
// the part table, or the vertices, before the faces that need them when those go out in chunks.
void read_elements_first(const InputFile& file, SoupBuilder& soup, PlyPartTable& parts,
                         PlyPass pass) {
  InputFile first(file.path());
  const PlyHeader header = read_header(first);
  const PlyLayout layout = find_layout(first, header);
  read_elements(first, header, layout, soup, parts, pass);
}

}  // namespace

TriangleSoup read_ply(InputFile& file, ReadReport& report, const SoupChunks* chunks) {
  const PlyHeader header = read_header(file);
  const PlyLayout layout = find_layout(file, header);
  check_counts_fit(file, header);
  SoupBuilder soup(file.name(), report, chunks);
  if (layout.parts == nullptr) soup.begin_part(file.path().stem().string());
  PlyPartTable parts(file, soup, layout.parts != nullptr);
  const std::uint64_t faces = layout.face != nullptr ? layout.face->count : 0;
  soup.reserve(layout.vertex->count, faces, file.size());
  if (chunks != nullptr && layout.parts != nullptr) {
    // The table follows the faces: read first.
    read_elements_first(file, soup, parts, kTablePass);
    parts.check(faces);
    parts.know_parts();
  }
  // Faces before their vertices (PLY allows it): the vertices read first when the faces go
  // out in chunks.
  const bool vertices_read_first = chunks != nullptr && !vertices_first(layout);
  if (vertices_read_first) {
    read_elements_first(file, soup, parts, kVerticesPass);
    // The pass opened the path again: a file replaced meanwhile is not read as this one.
    if (soup.vertex_count() != layout.vertex->count)
      throw FormatError(file.name() + ": the file changed while it was read (" +
                        std::to_string(soup.vertex_count()) + " vertices read where its header says " +
                        std::to_string(layout.vertex->count) + ")");
  }
  report.encoding = header.encoding == PlyEncoding::ascii               ? "ascii"
                    : header.encoding == PlyEncoding::binary_big_endian ? "binary_big_endian"
                                                                        : "binary_little_endian";
  read_elements(file, header, layout, soup, parts,
                PlyPass{!vertices_read_first, true, !parts.known()});
  if (!parts.known()) parts.apply(faces);
  return soup.finish();
}

}  // namespace tetrapage::detail
