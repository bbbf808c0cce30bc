// RGB images: what the renderer reads back and what `gradel render` and the render test write
// and read as PNG (stb_image_write / stb_image, Debian's libstb).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace gradel {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb;  ///< 3 bytes per pixel, rows top to bottom.

  const uint8_t* pixel(int x, int y) const { return &rgb[3 * (size_t(y) * size_t(width) + size_t(x))]; }
};

/// Writes a PNG. Throws InputError naming the path on failure.
void writePng(const std::string& path, const Image& image);
/// Reads a PNG (or any format stb_image reads) as RGB. Throws InputError naming the path.
Image readPng(const std::string& path);

/// Flips rows: OpenGL reads the bottom row first.
void flipRows(Image& image);

}  // namespace gradel
