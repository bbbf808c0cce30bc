#include "gradel/size_limits.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace gradel {

namespace {
// Measured bytes (World::memoryBytes() plus the Layout kept beside it by buildScene, on 32^3 and
// 64^3 boxes and spheres in each layout), rounded up: per unique vertex (rest position, mass,
// state, scratch, vertex -> element lists), per element (rest data, frames, layout record) and
// per element-vertex pair (ids, rest offsets, both directions).
constexpr double kBytesPerVertex = 260;
constexpr double kBytesPerElement = 400;
constexpr double kBytesPerPair = 48;
}  // namespace

uint64_t defaultMemoryLimit() {
  if (const char* env = std::getenv("GRADEL_MEMORY_LIMIT_MB")) {
    char* end = nullptr;
    const double mb = std::strtod(env, &end);
    if (end != env && *end == '\0' && mb > 0 && std::isfinite(mb)) return uint64_t(mb * 1024 * 1024);
  }
  const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || pageSize <= 0) return uint64_t(8) << 30;  // unknown: assume 8 GiB
  return uint64_t(double(pages) * double(pageSize) * 0.75);
}

uint64_t estimateVolumeBytes(const std::array<int, 3>& dims, int dim, bool labelled) {
  const double voxels = double(dims[0]) * double(dims[1]) * double(dim == 3 ? dims[2] : 1);
  const double lattice = (double(dims[0]) + 1) * (double(dims[1]) + 1) * (dim == 3 ? double(dims[2]) + 1 : 1);
  // The volume (1 byte, plus a 2-byte label when labelled), the next level's working volume (a
  // 2-byte label per cell, 1/2^dim cells), the vertex bitmap and its rank table (1.5 bits per
  // lattice point).
  return uint64_t(voxels * ((labelled ? 3.0 : 1.0) + 2.0 / (dim == 3 ? 8 : 4)) + lattice * 1.5 / 8);
}

uint64_t estimateModelBytes(const LayoutCounts& c, int /*dim*/) {
  return uint64_t(kBytesPerVertex * double(c.vertices) + kBytesPerElement * double(c.elements) +
                  kBytesPerPair * double(c.pairsEstimate));
}

std::string formatBytes(uint64_t bytes) {
  char buf[32];
  const double b = double(bytes);
  if (b >= 1e9)
    std::snprintf(buf, sizeof buf, "%.1f GB", b / 1e9);
  else if (b >= 1e6)
    std::snprintf(buf, sizeof buf, "%.1f MB", b / 1e6);
  else
    std::snprintf(buf, sizeof buf, "%.0f kB", b / 1e3);
  return buf;
}

void checkVolumeSize(const std::array<int, 3>& dims, int dim, const SizeLimits& limits, const std::string& key,
                     bool labelled) {
  const std::string grid = std::to_string(dims[0]) + " x " + std::to_string(dims[1]) +
                           (dim == 3 ? " x " + std::to_string(dims[2]) : std::string());
  for (int a = 0; a < dim; ++a)
    if (dims[a] < 1 || dims[a] > kMaxGridEdge)
      throw InputError(key + ": a grid of " + grid + " voxels (expected edges of 1 to " + std::to_string(kMaxGridEdge) +
                       ")");
  const uint64_t voxels = uint64_t(dims[0]) * uint64_t(dims[1]) * uint64_t(dim == 3 ? dims[2] : 1);
  if (voxels > limits.maxVoxels)
    throw InputError(key + ": a grid of " + grid + " = " + std::to_string(voxels) + " voxels is over the limit of " +
                     std::to_string(limits.maxVoxels) + " voxels (1024^3 in 3D)");
  const uint64_t bytes = estimateVolumeBytes(dims, dim, labelled);
  const uint64_t maxBytes = limits.maxBytes ? limits.maxBytes : defaultMemoryLimit();
  if (bytes > maxBytes)
    throw InputError(key + ": a grid of " + grid + " voxels needs about " + formatBytes(bytes) +
                     " for the volume alone, over the memory limit of " + formatBytes(maxBytes) +
                     " (3/4 of this machine's memory, or GRADEL_MEMORY_LIMIT_MB)");
}

void checkModelSize(const LayoutCounts& c, int dim, LayoutKind kind, const SizeLimits& limits, const std::string& key) {
  const uint64_t bytes = estimateModelBytes(c, dim);
  const uint64_t maxBytes = limits.maxBytes ? limits.maxBytes : defaultMemoryLimit();
  if (bytes > maxBytes)
    throw InputError(
        key + ": the " + layoutKindName(kind) + " layout of this body has " + std::to_string(c.elements) +
        " elements and " + std::to_string(c.vertices) + " vertices, which need about " + formatBytes(bytes) +
        ", over the memory limit of " + formatBytes(maxBytes) +
        " (3/4 of this machine's memory, or GRADEL_MEMORY_LIMIT_MB); use a smaller size or the gradational layout");
  if (limits.maxVertices && c.vertices > limits.maxVertices)
    throw InputError(key + ": the " + layoutKindName(kind) + " layout of this body has " + std::to_string(c.vertices) +
                     " vertices, over the limit of " + std::to_string(limits.maxVertices) + " vertices " +
                     limits.vertexLimitReason);
}

void checkLayoutSize(const VoxelVolume& volume, LayoutKind kind, const SizeLimits& limits, const std::string& key) {
  const int dim = volume.dim();
  const std::array<int, 3>& n = volume.dims();
  const uint64_t voxels = uint64_t(volume.size());
  LayoutCounts worst;
  worst.elements = voxels;
  worst.vertices = (uint64_t(n[0]) + 1) * (uint64_t(n[1]) + 1) * (dim == 3 ? uint64_t(n[2]) + 1 : 1);
  worst.pairsEstimate = (dim == 3 ? 27 : 9) * voxels;
  const uint64_t maxBytes = limits.maxBytes ? limits.maxBytes : defaultMemoryLimit();
  if (estimateModelBytes(worst, dim) <= maxBytes && (!limits.maxVertices || worst.vertices <= limits.maxVertices))
    return;  // fits whatever the layout: skip the count
  checkModelSize(countLayout(volume, kind), dim, kind, limits, key);
}

}  // namespace gradel
