#include "gradel/io/read_limits.h"

#include <charconv>
#include <cmath>

namespace gradel::io {

VoxelVolume allocateVolume(const ByteStream& in, const std::array<int64_t, 3>& dims, Real voxelSize,
                           const ReadLimits& limits, const std::string& what) {
  const std::string text = std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " + std::to_string(dims[2]);
  for (int64_t d : dims)
    if (d < 1 || d > limits.maxEdge)
      in.fail(what + ": " + text + " (expected every size in [1, " + std::to_string(limits.maxEdge) + "])");
  // Each factor is <= maxEdge (4096 = 2^12), so the product cannot overflow 64 bits.
  const uint64_t cells = uint64_t(dims[0]) * uint64_t(dims[1]) * uint64_t(dims[2]);
  if (cells > limits.maxVoxels)
    in.fail(what + ": " + text + " = " + std::to_string(cells) + " voxels is more than the limit of " +
            std::to_string(limits.maxVoxels));
  return VoxelVolume(3, int(dims[0]), int(dims[1]), int(dims[2]), voxelSize);
}

int64_t parseIntegerToken(const ByteStream& in, const std::string& token, const std::string& what) {
  int64_t v = 0;
  const char* end = token.data() + token.size();
  const char* begin = token.data() + (token.size() > 1 && token[0] == '+' ? 1 : 0);
  const auto r = std::from_chars(begin, end, v);
  if (r.ec == std::errc::result_out_of_range) in.fail(what + ": '" + token.substr(0, 30) + "' is out of range");
  if (r.ec != std::errc() || r.ptr != end || token.empty())
    in.fail(what + ": '" + token.substr(0, 30) + "' is not an integer");
  return v;
}

double parseNumberToken(const ByteStream& in, const std::string& token, const std::string& what) {
  double v = 0;
  const char* end = token.data() + token.size();
  const char* begin = token.data() + (token.size() > 1 && token[0] == '+' ? 1 : 0);
  const auto r = std::from_chars(begin, end, v);
  if (r.ec != std::errc() || r.ptr != end || token.empty() || !std::isfinite(v))
    in.fail(what + ": '" + token.substr(0, 30) + "' is not a finite number");
  return v;
}

}  // namespace gradel::io
