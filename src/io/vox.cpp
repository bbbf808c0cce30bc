#include "gradel/io/vox.h"

#include <cstring>
#include <vector>

namespace gradel::io {

namespace {

int32_t le32(const uint8_t* p) {
  return int32_t(uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24);
}

struct Chunk {
  std::string id;
  int64_t content = 0, children = 0;
};

// Reads a chunk header and checks that it fits in the `left` bytes of its parent.
Chunk readChunkHeader(ByteStream& in, int64_t left) {
  if (left < 12) in.fail("chunk: " + std::to_string(left) + " bytes left in the parent, a chunk header needs 12");
  uint8_t h[12];
  in.readExact(h, 12, "chunk header");
  Chunk c;
  for (int i = 0; i < 4; ++i) c.id.push_back(char(h[i]) >= 32 && char(h[i]) < 127 ? char(h[i]) : '?');
  c.content = le32(h + 4);
  c.children = le32(h + 8);
  if (c.content < 0 || c.children < 0)
    in.fail("chunk '" + c.id + "': negative size (" + std::to_string(c.content) + ", " + std::to_string(c.children) +
            ")");
  if (c.content + c.children > left - 12)
    in.fail("chunk '" + c.id + "': " + std::to_string(c.content + c.children) + " bytes do not fit in the " +
            std::to_string(left - 12) + " bytes left in its parent");
  return c;
}

}  // namespace

VoxelVolume readVox(ByteStream& in, Real voxelSize, int model, const ReadLimits& limits) {
  if (model < 0) in.fail("model index " + std::to_string(model) + " is negative");
  uint8_t head[8];
  in.readExact(head, 8, "header");
  if (std::memcmp(head, "VOX ", 4) != 0) in.fail("not a MagicaVoxel file (expected 'VOX ' at the start)");
  const int64_t fileLeft =
      in.remaining() ? int64_t(std::min<uint64_t>(*in.remaining(), uint64_t(1) << 40)) : int64_t(1) << 40;
  const Chunk main = readChunkHeader(in, fileLeft);
  if (main.id != "MAIN") in.fail("first chunk is '" + main.id + "' (expected 'MAIN')");
  in.skip(uint64_t(main.content), "MAIN content");

  int64_t left = main.children;
  int index = 0;  // models seen so far
  bool haveSize = false;
  std::array<int64_t, 3> size{0, 0, 0};
  while (left > 0) {
    const Chunk c = readChunkHeader(in, left);
    left -= 12 + c.content + c.children;
    if (c.id == "SIZE") {
      if (c.content < 12) in.fail("SIZE chunk: " + std::to_string(c.content) + " bytes (expected 12)");
      uint8_t s[12];
      in.readExact(s, 12, "SIZE chunk");
      for (int i = 0; i < 3; ++i) size[i] = le32(s + 4 * i);
      in.skip(uint64_t(c.content - 12 + c.children), "SIZE chunk");
      haveSize = true;
    } else if (c.id == "XYZI") {
      if (!haveSize) in.fail("XYZI chunk without a SIZE chunk before it");
      haveSize = false;
      if (index++ != model) {
        in.skip(uint64_t(c.content + c.children), "XYZI chunk");
        continue;
      }
      // File (x, y, z) z-up -> gradel (x, z, y) y-up, see vox.h.
      VoxelVolume v = allocateVolume(in, {size[0], size[2], size[1]}, voxelSize, limits, "SIZE chunk");
      if (c.content < 4) in.fail("XYZI chunk: " + std::to_string(c.content) + " bytes (expected at least 4)");
      uint8_t n4[4];
      in.readExact(n4, 4, "XYZI voxel count");
      const int64_t count = le32(n4);
      if (count < 0 || count > (c.content - 4) / 4)
        in.fail("XYZI chunk: voxel count " + std::to_string(count) + " does not fit in its " +
                std::to_string(c.content) + " bytes");
      std::vector<uint8_t> xyzi(size_t(count) * 4);
      in.readExact(xyzi.data(), xyzi.size(), "XYZI voxels");
      for (int64_t i = 0; i < count; ++i) {
        const uint8_t* p = &xyzi[size_t(i) * 4];
        const int x = p[0], y = p[1], z = p[2];
        if (x >= size[0] || y >= size[1] || z >= size[2])
          in.fail("XYZI voxel " + std::to_string(i) + " at (" + std::to_string(x) + ", " + std::to_string(y) + ", " +
                  std::to_string(z) + ") lies outside the model's SIZE");
        v.set(x, z, int(size[1] - 1 - y), true);
      }
      if (v.countFilled() == 0) in.fail("model " + std::to_string(model) + " has no voxels");
      return v;
    } else {
      in.skip(uint64_t(c.content + c.children), "chunk '" + c.id + "'");
    }
  }
  in.fail(index == 0 ? std::string("no model (no SIZE + XYZI chunks)")
                     : "model " + std::to_string(model) + " requested, the file has " + std::to_string(index));
}

}  // namespace gradel::io
