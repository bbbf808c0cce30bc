// Element layouts built from a voxel volume (paper sec. 3.1-3.2, figs. 4-6).
//
// Levels and cells
//   At level L the working volume has cells of edge 2^L voxels. An element is a 2x2x2 group
//   (2x2 in 2D) of level-L cells: its block is [origin, origin + 2 * cellSize) on each axis,
//   origin a multiple of 2 * cellSize. Cell c of the block (c = cx + 2*cy + 4*cz, each 0 or 1)
//   is bit c of `cellMask`.
//   * full group (all cells filled): the element's own vertices are the 8 (4 in 2D) corners
//     of the block;
//   * incomplete group (fig. 6): its own vertices are the corners of its filled cells;
//   * `voxel` layout: every filled voxel is an element with cellSize 1 and a single mask bit
//     (its block is the 2x2x2 voxel group holding it), so its own vertices are its 8 corners.
//   The element's region is the union of its filled cells (the whole block when full).
//
// Crack-free joins (fig. 5): an element also carries every vertex of the model that lies on the
//   closed boundary of its region ("hanging" vertices, from finer neighbours or from incomplete
//   neighbours at the same level). So every model vertex inside an element's closed region
//   belongs to that element.
//
// Placement (sec. 3.2), `gradational`: at each level, a group gets an element if it holds a
//   surface cell (a filled cell with an empty face neighbour, or one of another label, at that
//   level; see volume.h) or an empty cell (partly filled group) or two labels; those cells are then emptied, the volume
//   is halved, the element size doubles; repeat until the volume is empty. `uniform`: every group with a filled voxel
//   at level 0 is an element. `voxel`: one element per filled voxel.
//
// Numbering: vertices are sorted by lattice coordinate (z, then y, then x); elements by level,
//   then block origin (z, y, x), then (where several elements share a block: the voxel layout,
//   and blocks holding two labels) by their lowest cell index. Each element's vertex list is sorted by vertex id.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "gradel/volume.h"

namespace gradel {

enum class LayoutKind { Gradational, Uniform, Voxel };

LayoutKind parseLayoutKind(const std::string& name);  ///< "gradational" | "uniform" | "voxel"; InputError otherwise.
const char* layoutKindName(LayoutKind k);

struct Layout {
  int dim = 3;                       ///< 2 or 3.
  std::array<int, 3> dims{0, 0, 0};  ///< Volume size [voxels].
  Real voxelSize = 1;                ///< [m]
  LayoutKind kind = LayoutKind::Gradational;

  // ---- vertices ----
  std::vector<Int3> vertices;  ///< Lattice coordinates of each unique vertex [voxels], in (z, y, x) order.

  // ---- elements (one entry each) ----
  std::vector<uint8_t> level;     ///< Level L (0 = finest).
  std::vector<int32_t> cellSize;  ///< Cell edge [voxels]: 2^L (1 for the voxel layout).
  std::vector<Int3> origin;       ///< Lower corner of the 2x2x2 block [voxels].
  std::vector<uint8_t> cellMask;  ///< Filled cells of the block (bit cx + 2cy + 4cz).
  std::vector<uint16_t> label;    ///< Region label of every voxel of the element (1 for a binary volume).

  // ---- element -> vertex lists, compressed rows ----
  std::vector<uint32_t> elemStart;  ///< Size elements + 1; pairs of element e are [elemStart[e], elemStart[e+1]).
  std::vector<uint32_t> elemVerts;  ///< Vertex id of each element-vertex pair.
  std::vector<uint8_t> pairIsOwn;   ///< 1 if own (block corner if full, filled-cell corner if not), 0 if hanging.

  size_t numElements() const { return level.size(); }
  size_t numVertices() const { return vertices.size(); }
  size_t numPairs() const { return elemVerts.size(); }
  int numLevels() const;  ///< 1 + highest level.
  bool isFull(size_t e) const { return cellMask[e] == (dim == 3 ? 0xFF : 0x0F); }
  /// Lattice volume of element e's region [voxels^dim].
  int64_t regionVoxels(size_t e) const;
  /// Per lattice row (y, z), row z (dims[1] + 1) + y: where its vertices begin in `vertices`
  /// ((dims[1] + 1)(dims[2] + 1) + 1 entries, the last = numVertices(); indexVertices()).
  std::vector<uint32_t> rowStart;
  /// The vertex at lattice point p, or kNoVertex: the one lattice-to-vertex lookup. A binary
  /// search of p's row (rowStart) when the index is there (buildLayout makes it), else of all
  /// `vertices` (a layout made by hand), which are sorted by (z, y, x).
  uint32_t vertexAt(const Int3& p) const;
  /// Makes rowStart from `vertices` (sorted by (z, y, x), every one in [0, dims]). With it, a
  /// carving event's re-layout and rest model on a 64^3 box looked up 2-3x faster (vertexAt was
  /// 23 % of the event: ~14 steps of a search over 17,000 vertices, now ~5 over a row's dozens).
  void indexVertices();
  static constexpr uint32_t kNoVertex = UINT32_MAX;
};

struct LayoutStats {
  size_t voxels = 0;  ///< Filled voxels.
  size_t elements = 0;
  std::vector<size_t> elementsPerLevel;  ///< Index = level.
  size_t uniqueVertices = 0;
  size_t pairs = 0;            ///< Element-vertex pairs ("8 n^3" counting of the paper).
  size_t hangingVertices = 0;  ///< Unique vertices that are hanging in at least one element.
  size_t hangingPairs = 0;     ///< Pairs with pairIsOwn == 0.
};

/// Counts of a layout without building it (no element-vertex lists): exact elements and unique
/// vertices, and an estimate of the pairs (3^dim per element, exact for the voxel layout). Costs
/// the placement and a 1.5-bit-per-lattice-point vertex set; for the voxel layout no placement.
/// Throws InputError on an empty volume.
struct LayoutCounts {
  uint64_t elements = 0;
  uint64_t vertices = 0;
  uint64_t pairsEstimate = 0;
};
LayoutCounts countLayout(const VoxelVolume& volume, LayoutKind kind);

/// layoutStats of the voxel layout (one element per filled voxel, the paper's baseline), counted
/// without building it: elements = voxels, pairs = 2^dim per voxel, no hanging vertices.
LayoutStats voxelLayoutStats(const VoxelVolume& volume);

/// Builds the layout. Throws InputError on an empty volume.
Layout buildLayout(const VoxelVolume& volume, LayoutKind kind);
LayoutStats layoutStats(const Layout& layout, const VoxelVolume& volume);

}  // namespace gradel
