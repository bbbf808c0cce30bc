#include "gradel/render/layout_picture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace gradel::render {

namespace {
// Base colour of a label: a fixed palette (labels 1..6), then repeated.
std::array<double, 3> labelColour(uint16_t label) {
  static const std::array<double, 3> kPalette[] = {
      {0.93, 0.55, 0.45}, {0.35, 0.55, 0.85}, {0.45, 0.75, 0.45},
      {0.85, 0.75, 0.35}, {0.65, 0.45, 0.80}, {0.40, 0.75, 0.75},
  };
  return kPalette[(label - 1) % 6];
}
}  // namespace

Image layoutPicture(const Layout& layout, int slice, int pixelsPerVoxel) {
  const int nx = layout.dims[0], ny = layout.dims[1], nz = layout.dims[2];
  if (slice < 0 || slice >= nz) throw InputError("layout picture: slice " + std::to_string(slice) + " is outside the grid");
  if (pixelsPerVoxel < 3) throw InputError("layout picture: at least 3 pixels per voxel");
  // Owner element of every voxel of the slice (-1: empty).
  std::vector<int64_t> owner(size_t(nx) * size_t(ny), -1);
  for (size_t e = 0; e < layout.numElements(); ++e) {
    const int c = layout.cellSize[e];
    for (int bit = 0; bit < (layout.dim == 3 ? 8 : 4); ++bit) {
      if (!(layout.cellMask[e] >> bit & 1)) continue;
      const Int3 lo = layout.origin[e] + c * Int3(bit & 1, bit >> 1 & 1, bit >> 2 & 1);
      const int cz = layout.dim == 3 ? c : 1;
      if (slice < lo.z() || slice >= lo.z() + cz) continue;
      for (int y = lo.y(); y < std::min(lo.y() + c, ny); ++y)
        for (int x = lo.x(); x < std::min(lo.x() + c, nx); ++x) owner[size_t(x) + size_t(nx) * size_t(y)] = int64_t(e);
    }
  }
  const int top = layout.numLevels() - 1;
  auto ownerAt = [&](int x, int y) -> int64_t {
    return x < 0 || y < 0 || x >= nx || y >= ny ? -1 : owner[size_t(x) + size_t(nx) * size_t(y)];
  };
  auto labelOf = [&](int64_t e) -> int { return e < 0 ? 0 : layout.label.empty() ? 1 : layout.label[size_t(e)]; };
  const int p = pixelsPerVoxel;
  Image img;
  img.width = (nx + 2) * p;
  img.height = (ny + 2) * p;
  img.rgb.assign(size_t(img.width) * size_t(img.height) * 3, 255);
  for (int py = 0; py < img.height; ++py)
    for (int px = 0; px < img.width; ++px) {
      const int x = px / p - 1, y = (img.height - 1 - py) / p - 1;  // voxel; y up
      const int u = px % p, v = p - 1 - (img.height - 1 - py) % p;   // pixel inside the voxel, v from the top
      const int64_t e = ownerAt(x, y);
      if (e < 0) continue;
      // Element borders: the voxel's edge pixels towards a voxel of another element (1 pixel),
      // or of another label or empty space (2 pixels).
      std::array<double, 3> rgb = labelColour(uint16_t(labelOf(e)));
      const double lighten = top > 0 ? 0.55 * layout.level[size_t(e)] / top : 0.0;
      for (double& ch : rgb) ch = ch + (1 - ch) * lighten;
      const int64_t nb[4] = {ownerAt(x - 1, y), ownerAt(x + 1, y), ownerAt(x, y + 1), ownerAt(x, y - 1)};
      const int dist[4] = {u, p - 1 - u, v, p - 1 - v};  // pixels to the left, right, top, bottom edge
      for (int k = 0; k < 4; ++k) {
        if (nb[k] == e) continue;
        const bool region = labelOf(nb[k]) != labelOf(e);
        if (dist[k] < (region ? 2 : 1)) rgb = region ? std::array<double, 3>{0, 0, 0} : std::array<double, 3>{0.3, 0.3, 0.3};
      }
      uint8_t* out = &img.rgb[3 * (size_t(py) * size_t(img.width) + size_t(px))];
      for (int ch = 0; ch < 3; ++ch) out[ch] = uint8_t(std::lround(255 * std::clamp(rgb[ch], 0.0, 1.0)));
    }
  return img;
}

}  // namespace gradel::render
