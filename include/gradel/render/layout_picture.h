// A flat picture of a layout's elements in one z slice (docs/layout.md): each voxel coloured by
// its element's region label (hue) and level (lighter = coarser), thin dark lines between
// elements and thick black lines where two labels meet. GL-free: pure pixels, written as PNG by
// image.h.
#pragma once

#include "gradel/image.h"
#include "gradel/layout.h"

namespace gradel::render {

/// The layout's slice z = `slice` (0 in 2D), `pixelsPerVoxel` pixels per voxel edge, rows top to
/// bottom with y up (row 0 is the top of the grid), a margin of one voxel. Throws InputError for
/// a slice outside the grid or pixelsPerVoxel < 3.
Image layoutPicture(const Layout& layout, int slice, int pixelsPerVoxel);

}  // namespace gradel::render
