#include "gradel/io/binvox.h"

#include <sstream>
#include <vector>

namespace gradel::io {

namespace {
std::vector<std::string> tokens(const std::string& line) {
  std::istringstream s(line);
  std::vector<std::string> out;
  for (std::string t; s >> t;) out.push_back(t);
  return out;
}
}  // namespace

VoxelVolume readBinvox(ByteStream& in, Real voxelSize, const ReadLimits& limits) {
  constexpr size_t kMaxLine = 256;  // header lines are short; a long one means binary data
  const auto magic = in.readLine(kMaxLine, "header");
  if (!magic || magic->rfind("#binvox", 0) != 0) in.fail("not a binvox file (expected '#binvox 1' on the first line)");
  std::array<int64_t, 3> dim{0, 0, 0};
  bool haveDim = false;
  for (int lines = 0;; ++lines) {
    if (lines > 64) in.fail("header: no 'data' line within 64 lines");
    const auto line = in.readLine(kMaxLine, "header");
    if (!line) in.fail("truncated: header ends before the 'data' line");
    const std::vector<std::string> t = tokens(*line);
    if (t.empty()) continue;
    if (t[0] == "data") break;
    if (t[0] == "dim") {
      if (t.size() != 4) in.fail("header: 'dim' needs 3 integers, got '" + line->substr(0, 60) + "'");
      for (int i = 0; i < 3; ++i) dim[i] = parseIntegerToken(in, t[i + 1], "header: dim[" + std::to_string(i) + "]");
      haveDim = true;
    } else if (t[0] == "translate") {
      if (t.size() != 4) in.fail("header: 'translate' needs 3 numbers");
      for (int i = 0; i < 3; ++i) parseNumberToken(in, t[i + 1], "header: translate");
    } else if (t[0] == "scale") {
      if (t.size() != 2) in.fail("header: 'scale' needs 1 number");
      parseNumberToken(in, t[1], "header: scale");
    } else {
      in.fail("header: unknown line '" + line->substr(0, 40) + "' (expected dim, translate, scale or data)");
    }
  }
  if (!haveDim) in.fail("header: no 'dim' line before 'data'");
  // File order (x, z, y) with sizes (D, H, W): gradel nx = D, nz = H, ny = W.
  const int64_t D = dim[0], H = dim[1], W = dim[2];
  VoxelVolume v = allocateVolume(in, {D, W, H}, voxelSize, limits, "header: dim");
  const uint64_t total = v.size();
  uint8_t* out = v.data().data();
  const uint64_t perX = uint64_t(W) * uint64_t(H);
  uint64_t n = 0;  // voxels decoded so far, in file order
  std::vector<uint8_t> buf(1u << 16);
  // read() returns less than asked only at the end of the data, so an odd count means the last
  // (value, count) pair is cut.
  for (size_t got = buf.size(); n < total && got == buf.size();) {
    got = in.read(buf.data(), buf.size());
    for (size_t p = 0; p < got; p += 2) {
      if (n == total) in.fail("run-length data: unexpected bytes after the last run");
      if (p + 1 == got) in.fail("truncated: run-length data ends in the middle of a (value, count) pair");
      const uint64_t count = buf[p + 1];
      if (count > total - n)
        in.fail("run-length data: runs cover more than dim's " + std::to_string(total) + " voxels");
      if (buf[p] != 0)
        for (uint64_t m = n; m < n + count; ++m) {
          const uint64_t x = m / perX, rest = m % perX, z = rest / uint64_t(W), y = rest % uint64_t(W);
          out[v.index(int(x), int(y), int(z))] = 1;
        }
      n += count;
    }
  }
  if (n < total)
    in.fail("truncated: run-length data covers " + std::to_string(n) + " of dim's " + std::to_string(total) +
            " voxels");
  uint8_t extra = 0;
  if (in.read(&extra, 1) != 0) in.fail("run-length data: unexpected bytes after the last run");
  return v;
}

}  // namespace gradel::io
