// How big a body may be, checked before anything large is allocated (docs/scenes.md, "Limits").
//
// Two checks, each an InputError naming the key that sets the size (`body.size`, `body.grid`,
// `body.source`, `--size`) and the estimate against the limit:
//   1. before the volume is made: the grid's voxel count against kMaxBodyVoxels, and the
//      volume's bytes against the memory limit;
//   2. before the layout is built: the element and vertex counts (countLayout, layout.h: the
//      placement and the vertex set, no element-vertex lists) give the bytes of layout, rest
//      model and world, against the memory limit.
// The memory limit is 3/4 of the machine's physical memory, or GRADEL_MEMORY_LIMIT_MB.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "gradel/layout.h"

namespace gradel {

/// Largest voxel grid of a body: 2^30 voxels (1024^3 in 3D; a 2D grid reaches 4096^2 first),
/// which holds the volume in 1 GiB.
inline constexpr uint64_t kMaxBodyVoxels = uint64_t(1) << 30;
/// Largest grid edge [voxels] (scene files, `gradel layout --size`, volume files).
inline constexpr int kMaxGridEdge = 4096;

struct SizeLimits {
  uint64_t maxVoxels = kMaxBodyVoxels;
  uint64_t maxBytes = 0;  ///< 0: defaultMemoryLimit().
  /// Most vertices a body may have (0: no limit), checked with the layout's counts before the
  /// layout is built (check 2): what a run's step budget allows (`gradel run`, run_budget.h),
  /// with `vertexLimitReason` saying so in the message.
  uint64_t maxVertices = 0;
  std::string vertexLimitReason;
};

/// 3/4 of physical memory, or the environment variable GRADEL_MEMORY_LIMIT_MB when set (> 0).
uint64_t defaultMemoryLimit();

/// Bytes to make the volume (1 per voxel, 3 with region labels) and scan it (the coarser working
/// volumes, the vertex bitmap): an upper bound before any layout.
uint64_t estimateVolumeBytes(const std::array<int, 3>& dims, int dim, bool labelled = false);
/// Bytes of layout, rest model and world for a layout with these counts (measured costs per
/// vertex, element and element-vertex pair, see size_limits.cpp).
uint64_t estimateModelBytes(const LayoutCounts& counts, int dim);

/// Check 1: throws InputError "KEY: ..." when the grid exceeds the voxel count or memory limit.
void checkVolumeSize(const std::array<int, 3>& dims, int dim, const SizeLimits& limits, const std::string& key,
                     bool labelled = false);
/// Check 2: throws InputError "KEY: ..." when the model's estimated bytes exceed the limit, or
/// its vertices exceed limits.maxVertices.
void checkModelSize(const LayoutCounts& counts, int dim, LayoutKind kind, const SizeLimits& limits,
                    const std::string& key);

/// Check 2 for a volume at hand: counts the layout (countLayout) unless even one element and
/// 3^dim pairs per voxel would fit, then checkModelSize.
void checkLayoutSize(const VoxelVolume& volume, LayoutKind kind, const SizeLimits& limits, const std::string& key);

/// "1.2 GB": bytes for messages.
std::string formatBytes(uint64_t bytes);

}  // namespace gradel
