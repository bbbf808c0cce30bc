// MagicaVoxel .vox (github.com/ephtracy/voxel-model, MagicaVoxel-file-format-vox.txt):
// "VOX " + version, then RIFF-style chunks (id, content bytes, children bytes; little endian):
// MAIN holds an optional PACK (model count) and one SIZE (x, y, z) + XYZI (count, then x, y, z,
// colour index bytes) pair per model; palette, materials and the scene graph (RGBA, MATL, nTRN,
// nGRP, nSHP, LAYR, ...) are skipped.
//
// Axes: MagicaVoxel is z-up; gradel's scenes are y-up (gravity -y), so a model is turned a
// quarter about x: file (x, y, z) -> gradel (i, j, k) = (x, z, sizeY - 1 - y). A proper
// rotation, so the model is not mirrored.
#pragma once

#include "gradel/io/byte_stream.h"
#include "gradel/io/read_limits.h"
#include "gradel/volume.h"

namespace gradel::io {

/// Reads model `model` (0 = the first) of a .vox file; every voxel of the model is filled,
/// whatever its colour. InputError for anything malformed or a model index out of range.
VoxelVolume readVox(ByteStream& in, Real voxelSize, int model = 0, const ReadLimits& limits = {});

}  // namespace gradel::io
