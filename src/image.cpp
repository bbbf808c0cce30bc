#include "gradel/image.h"

#include <stb_image.h>
#include <stb_image_write.h>
#include <algorithm>

#include "gradel/types.h"

namespace gradel {

void writePng(const std::string& path, const Image& image) {
  if (image.width <= 0 || image.height <= 0 || image.rgb.size() != size_t(image.width) * size_t(image.height) * 3)
    throw InputError(path + ": image has no pixels or a wrong buffer size");
  if (!stbi_write_png(path.c_str(), image.width, image.height, 3, image.rgb.data(), image.width * 3))
    throw InputError(path + ": cannot write PNG");
}

Image readPng(const std::string& path) {
  int w = 0, h = 0, channels = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &channels, 3);
  if (!data)
    throw InputError(path + ": cannot read image: " + (stbi_failure_reason() ? stbi_failure_reason() : "unknown"));
  Image img;
  img.width = w;
  img.height = h;
  img.rgb.assign(data, data + size_t(w) * size_t(h) * 3);
  stbi_image_free(data);
  return img;
}

void flipRows(Image& image) {
  const size_t row = size_t(image.width) * 3;
  for (int y = 0; y < image.height / 2; ++y)
    std::swap_ranges(image.rgb.begin() + std::ptrdiff_t(row * size_t(y)),
                     image.rgb.begin() + std::ptrdiff_t(row * size_t(y + 1)),
                     image.rgb.begin() + std::ptrdiff_t(row * size_t(image.height - 1 - y)));
}

}  // namespace gradel
