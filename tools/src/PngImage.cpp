#include "tetrapage/tools/PngImage.h"

#include <zlib.h>

#include <array>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/FileChecks.h"
#include "tetrapage/formats/mesh/OutputFile.h"

namespace tetrapage {
namespace {

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(std::uint8_t(v >> shift));
}

std::uint32_t get_u32(const std::uint8_t* p) {
  return std::uint32_t(p[0]) << 24 | std::uint32_t(p[1]) << 16 | std::uint32_t(p[2]) << 8 | p[3];
}

void put_chunk(std::vector<std::uint8_t>& out, const char type[4], const std::vector<std::uint8_t>& data) {
  put_u32(out, std::uint32_t(data.size()));
  const std::size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  put_u32(out, std::uint32_t(crc32(0, out.data() + start, uInt(out.size() - start))));
}

constexpr std::array<std::uint8_t, 8> kSignature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

}  // namespace

void write_png(const std::filesystem::path& path, const RgbImage& image) {
  if (image.width == 0 || image.height == 0 || image.pixels.size() != 3 * image.width * image.height)
    throw InputError("image for '" + path.string() + "' is empty or inconsistent");
  // Each row: filter byte 0 (none), then the pixels.
  const std::size_t row = 3 * image.width;
  std::vector<std::uint8_t> raw;
  raw.reserve((row + 1) * image.height);
  for (std::size_t y = 0; y < image.height; ++y) {
    raw.push_back(0);
    raw.insert(raw.end(), image.pixels.begin() + std::ptrdiff_t(y * row),
               image.pixels.begin() + std::ptrdiff_t((y + 1) * row));
  }
  uLongf packed_size = compressBound(uLong(raw.size()));
  std::vector<std::uint8_t> packed(packed_size);
  if (compress2(packed.data(), &packed_size, raw.data(), uLong(raw.size()), 6) != Z_OK)
    throw Error("zlib could not compress the image for '" + path.string() + "'");
  packed.resize(packed_size);

  std::vector<std::uint8_t> file(kSignature.begin(), kSignature.end());
  std::vector<std::uint8_t> header;
  put_u32(header, std::uint32_t(image.width));
  put_u32(header, std::uint32_t(image.height));
  header.insert(header.end(), {8, 2, 0, 0, 0});  // 8 bits, RGB, deflate, filter set 0, no interlace
  put_chunk(file, "IHDR", header);
  put_chunk(file, "IDAT", packed);
  put_chunk(file, "IEND", {});

  OutputFile out(path);
  out.write(file.data(), file.size());
  out.commit();
}

RgbImage read_png(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot read '" + path.string() + "'");
  const std::vector<std::uint8_t> file{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const std::string where = path.string();
  if (file.size() < 8 || !std::equal(kSignature.begin(), kSignature.end(), file.begin()))
    throw FormatError(where + ": not a PNG");
  std::size_t at = 8, width = 0, height = 0;
  std::vector<std::uint8_t> packed;
  while (at + 12 <= file.size()) {
    const std::uint32_t length = get_u32(&file[at]);
    if (at + 12 + std::size_t(length) > file.size()) throw FormatError(where + ": truncated chunk");
    const std::string type(reinterpret_cast<const char*>(&file[at + 4]), 4);
    const std::uint8_t* data = &file[at + 8];
    if (get_u32(data + length) != std::uint32_t(crc32(0, &file[at + 4], uInt(length + 4))))
      throw FormatError(where + ": bad CRC in chunk " + type);
    if (type == "IHDR") {
      if (length != 13 || data[8] != 8 || data[9] != 2 || data[12] != 0)
        throw FormatError(where + ": not an 8-bit RGB non-interlaced PNG");
      width = get_u32(data);
      height = get_u32(data + 4);
    } else if (type == "IDAT") {
      packed.insert(packed.end(), data, data + length);
    }
    at += 12 + length;
  }
  if (width == 0 || height == 0) throw FormatError(where + ": no IHDR");
  std::vector<std::uint8_t> raw((3 * width + 1) * height);
  uLongf raw_size = uLongf(raw.size());
  if (uncompress(raw.data(), &raw_size, packed.data(), uLong(packed.size())) != Z_OK || raw_size != raw.size())
    throw FormatError(where + ": bad image data");
  RgbImage image(width, height);
  for (std::size_t y = 0; y < height; ++y) {
    if (raw[y * (3 * width + 1)] != 0) throw FormatError(where + ": row filter other than none");
    std::memcpy(image.at(0, y), &raw[y * (3 * width + 1) + 1], 3 * width);
  }
  return image;
}

}  // namespace tetrapage
