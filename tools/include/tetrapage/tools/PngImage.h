#pragma once
/// @file PngImage.h
/// An 8-bit RGB image and its PNG encoding (zlib's deflate and CRC), for tetrapage render.

#include <cstdint>
#include <filesystem>
#include <vector>

namespace tetrapage {

struct RgbImage {
  std::size_t width = 0, height = 0;
  std::vector<std::uint8_t> pixels;  ///< row-major, top row first, 3 bytes per pixel

  RgbImage(std::size_t w, std::size_t h) : width(w), height(h), pixels(3 * w * h, 0) {}
  std::uint8_t* at(std::size_t x, std::size_t y) { return &pixels[3 * (y * width + x)]; }
  const std::uint8_t* at(std::size_t x, std::size_t y) const { return &pixels[3 * (y * width + x)]; }
};

/// Writes the image as a PNG (8-bit RGB, no interlace) under `<path>.tmp`, renamed when
/// complete. @throw InputError for an empty image; IoError naming the file on failure.
void write_png(const std::filesystem::path& path, const RgbImage& image);

/// Decodes a PNG written by write_png (8-bit RGB, filter 0 on every row): for the tests.
/// @throw FormatError for anything else.
RgbImage read_png(const std::filesystem::path& path);

}  // namespace tetrapage
