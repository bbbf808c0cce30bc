// The layout builder (paper sec. 3.1-3.2, figs. 4-6): voxel volume -> elements -> vertices.
//
// Three stages, each a function over the previous one's output:
//   1. placement: scan the working volume level by level and emit one `Placed` record per
//      element (level, cell size, block origin, cell mask), already in numbering order;
//   2. vertices: the union of every element's own vertices (block corners of a full element,
//      corners of the filled cells of an incomplete one), kept as a bitmap over the lattice so
//      that a vertex's id is its rank in (z, y, x) order;
//   3. closure (fig. 5): every element additionally takes each model vertex on the boundary of
//      its region, found by walking the lattice points of the region's boundary faces and
//      testing them in the bitmap. The cost is O(sum over elements of their boundary lattice
//      points) time and 1.5 bits per lattice point of memory; no int32 index grid.
#include "gradel/layout.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cstdint>
#include <stdexcept>

namespace gradel {

namespace {

/// One element as placed, before its vertex list is known.
struct Placed {
  uint8_t level;     ///< Level L.
  int32_t cellSize;  ///< Cell edge [voxels].
  Int3 origin;       ///< Lower block corner [voxels].
  uint8_t mask;      ///< Filled cells, bit cx + 2cy + 4cz.
  uint16_t label;    ///< The region label of every cell of the element (1 in a binary volume).
};

/// Read-only view of one level's working volume: n[0] x n[1] x n[2] cells, x fastest, each
/// holding its label (0 = empty). `T` is uint8_t for a binary volume's level 0 (any non-zero
/// byte is label 1) and uint16_t for labels. Out-of-grid cells (including the padding of odd
/// sizes) read as empty.
template <class T>
struct GridView {
  std::array<int, 3> n;
  const T* cells;

  uint16_t at(int i, int j, int k) const {
    if (i < 0 || j < 0 || k < 0 || i >= n[0] || j >= n[1] || k >= n[2]) return 0;
    const T v = cells[size_t(i) + size_t(n[0]) * (size_t(j) + size_t(n[1]) * size_t(k))];
    if constexpr (sizeof(T) == 1)
      return v != 0 ? 1 : 0;
    else
      return v;
  }
  /// at() for a cell known to be inside the grid.
  uint16_t in(int i, int j, int k) const {
    const T v = cells[size_t(i) + size_t(n[0]) * (size_t(j) + size_t(n[1]) * size_t(k))];
    if constexpr (sizeof(T) == 1)
      return v != 0 ? 1 : 0;
    else
      return v;
  }
  /// Whether the 2x2x2 group with first cell (bx, by, bz) and its face neighbours are all inside.
  bool groupInside(int bx, int by, int bz, int dim) const {
    return bx >= 1 && by >= 1 && bx + 2 < n[0] && by + 2 < n[1] && (dim == 2 || (bz >= 1 && bz + 2 < n[2]));
  }
};

int cellCount(int dim) { return dim == 3 ? 8 : 4; }
uint8_t fullMask(int dim) { return dim == 3 ? 0xFF : 0x0F; }
/// Cell c of a block sits at (cx, cy, cz) = bits 0, 1, 2 of c.
int cellCoord(int c, int axis) { return (c >> axis) & 1; }

/// Scans one level in 2x2x2 groups (2x2 in 2D; odd sizes are padded with empty cells), appends
/// the elements it places to `out` in (z, y, x) block order, and returns the next level's working
/// volume (each group -> one cell). `kind` selects the rule (sec. 3.2 step 1):
///   Gradational: a group with a filled cell gets an element if it is partly filled, holds two
///     labels, or one of its cells is a surface cell (a face neighbour, possibly in another group,
///     that is empty or of another label: a border between two regions counts as surface);
///   Uniform: every group with a filled cell gets one;
///   Voxel: every filled cell becomes its own single-cell element.
/// A placed group holding several labels becomes one element per label (its cells of that label,
/// in the order of each label's first cell), so no element mixes two regions; with one label this
/// is the paper's one element per group.
/// Borders between labels (gradational, `labelled`): where a group is placed because it touches
/// another label (or holds two), every filled group of its parent block (the 2x2x2 groups that
/// make one group of the next level) is placed too. Without that, the border's layer of fine
/// elements is one group thick, and the next level's group behind it is incomplete: a plate
/// parallel to the border (fig. 6), 3/8 as stiff across itself as along (material.h), so a bar of
/// two materials in series was 1.7 % softer than its halves (docs/layout.md). With it, the fine
/// layer is a whole parent block thick and the levels behind an aligned border are complete
/// elements. A binary volume has no such border: the paper's rule, unchanged.
/// Decisions read the level's volume as it was at the start of the scan, so they do not depend
/// on scan order; the groups that got elements are "emptied" (step 2) by writing 0 into the next
/// level (step 3), where a cell holds the group's label iff the group was full of one label and
/// got no element.
template <class T>
std::vector<uint16_t> scanLevel(const GridView<T>& g, int dim, int level, LayoutKind kind, bool labelled,
                                std::vector<Placed>& out, std::array<int, 3>& nextDims) {
  const int groupsZ = dim == 3 ? (g.n[2] + 1) / 2 : 1;
  nextDims = {(g.n[0] + 1) / 2, (g.n[1] + 1) / 2, groupsZ};
  const size_t groups = size_t(nextDims[0]) * size_t(nextDims[1]) * size_t(nextDims[2]);
  std::vector<uint16_t> next(groups, 0);
  const int cs = 1 << level;  // cell edge [voxels]
  const int cells = cellCount(dim);
  const uint8_t full = fullMask(dim);
  // The group at (gx, gy, gz): its filled cells' mask, their labels, and whether it is mixed.
  auto readGroup = [&](int gx, int gy, int gz, uint16_t* lab, uint16_t& first, bool& mixed) {
    const int bx = 2 * gx, by = 2 * gy, bz = dim == 3 ? 2 * gz : 0;  // first cell of the group
    const bool inside = g.groupInside(bx, by, bz, dim);
    uint8_t mask = 0;
    first = 0;  // label of the group's first filled cell
    mixed = false;
    for (int c = 0; c < cells; ++c) {
      const int i = bx + cellCoord(c, 0), j = by + cellCoord(c, 1), k = bz + cellCoord(c, 2);
      lab[c] = inside ? g.in(i, j, k) : g.at(i, j, k);
      if (lab[c] == 0) continue;
      mask |= uint8_t(1u << c);
      if (first == 0) first = lab[c];
      mixed = mixed || lab[c] != first;
    }
    return mask;
  };
  // Does a filled cell of the group have a face neighbour of another non-zero label?
  auto touchesOtherLabel = [&](int gx, int gy, int gz, const uint16_t* lab) {
    const int bx = 2 * gx, by = 2 * gy, bz = dim == 3 ? 2 * gz : 0;
    for (int c = 0; c < cells; ++c) {
      if (lab[c] == 0) continue;
      const int i = bx + cellCoord(c, 0), j = by + cellCoord(c, 1), k = bz + cellCoord(c, 2);
      for (int ax = 0; ax < dim; ++ax)
        for (int d = -1; d <= 1; d += 2) {
          const uint16_t n = g.at(i + (ax == 0) * d, j + (ax == 1) * d, k + (ax == 2) * d);
          if (n != 0 && n != lab[c]) return true;
        }
    }
    return false;
  };
  // The paper's placement rule for one group (see above), given its filled cells.
  auto paperRule = [&](int gx, int gy, int gz, uint8_t mask, uint16_t first, bool mixed) {
    if (kind == LayoutKind::Uniform || mask != full || mixed) return true;
    // A full group of one label: inner face neighbours are of its label, so only the outward
    // neighbour of each cell on each axis can make it a surface cell (empty or another label).
    const int bx = 2 * gx, by = 2 * gy, bz = dim == 3 ? 2 * gz : 0;
    const bool inside = g.groupInside(bx, by, bz, dim);
    auto get = [&](int i, int j, int k) { return inside ? g.in(i, j, k) : g.at(i, j, k); };
    for (int c = 0; c < cells; ++c) {
      const int i = bx + cellCoord(c, 0), j = by + cellCoord(c, 1), k = bz + cellCoord(c, 2);
      const int di = cellCoord(c, 0) ? 1 : -1, dj = cellCoord(c, 1) ? 1 : -1, dk = cellCoord(c, 2) ? 1 : -1;
      if (get(i + di, j, k) != first || get(i, j + dj, k) != first || (dim == 3 && get(i, j, k + dk) != first))
        return true;
    }
    return false;
  };
  uint16_t lab[8];
  // Borders between labels: the parent blocks that hold a group placed at a border.
  const std::array<int, 3> blocks{(nextDims[0] + 1) / 2, (nextDims[1] + 1) / 2, (nextDims[2] + 1) / 2};
  auto blockOf = [&](int gx, int gy, int gz) {
    return size_t(gx / 2) + size_t(blocks[0]) * (size_t(gy / 2) + size_t(blocks[1]) * size_t(gz / 2));
  };
  std::vector<char> borderBlock;
  if (labelled && kind == LayoutKind::Gradational) {
    borderBlock.assign(size_t(blocks[0]) * size_t(blocks[1]) * size_t(blocks[2]), 0);
    for (int gz = 0; gz < nextDims[2]; ++gz)
      for (int gy = 0; gy < nextDims[1]; ++gy)
        for (int gx = 0; gx < nextDims[0]; ++gx) {
          uint16_t first;
          bool mixed;
          const uint8_t mask = readGroup(gx, gy, gz, lab, first, mixed);
          if (mask != 0 && (mixed || touchesOtherLabel(gx, gy, gz, lab))) borderBlock[blockOf(gx, gy, gz)] = 1;
        }
  }
  size_t nextIndex = 0;
  for (int gz = 0; gz < nextDims[2]; ++gz)
    for (int gy = 0; gy < nextDims[1]; ++gy)
      for (int gx = 0; gx < nextDims[0]; ++gx, ++nextIndex) {
        uint16_t first;
        bool mixed;
        const uint8_t mask = readGroup(gx, gy, gz, lab, first, mixed);
        if (mask == 0) continue;
        const Int3 origin(2 * gx * cs, 2 * gy * cs, dim == 3 ? 2 * gz * cs : 0);
        if (kind == LayoutKind::Voxel) {
          for (int c = 0; c < cells; ++c)
            if (mask & (1u << c)) out.push_back({uint8_t(level), cs, origin, uint8_t(1u << c), lab[c]});
          continue;
        }
        const bool place =
            paperRule(gx, gy, gz, mask, first, mixed) || (!borderBlock.empty() && borderBlock[blockOf(gx, gy, gz)]);
        if (place) {
          if (!mixed) {
            out.push_back({uint8_t(level), cs, origin, mask, first});
            continue;
          }
          uint8_t done = 0;  // cells already given to an element
          for (int c = 0; c < cells; ++c) {
            if (!(mask & ~done & (1u << c))) continue;
            uint8_t part = 0;
            for (int d = c; d < cells; ++d)
              if (lab[d] == lab[c]) part |= uint8_t(1u << d);
            done |= part;
            out.push_back({uint8_t(level), cs, origin, part, lab[c]});
          }
        } else {
          // Step 3 of sec. 3.2: an unplaced group can only be full of one label (a partial or
          // mixed one always gets an element), so halving never meets a mixed group.
          assert(mask == full && !mixed);
          next[nextIndex] = first;
        }
      }
  return next;
}

/// Placement for every kind, in numbering order (level, then block origin (z, y, x), then cell).
std::vector<Placed> place(const VoxelVolume& volume, LayoutKind kind) {
  std::vector<Placed> out;
  const int dim = volume.dim();
  std::array<int, 3> dims = volume.dims();
  std::array<int, 3> nextDims{};
  std::vector<uint16_t> next =
      volume.hasLabels()
          ? scanLevel(GridView<uint16_t>{dims, volume.labels().data()}, dim, 0, kind, true, out, nextDims)
          : scanLevel(GridView<uint8_t>{dims, volume.data().data()}, dim, 0, kind, false, out, nextDims);
  if (kind != LayoutKind::Gradational) return out;
  // Gradational: halve and repeat until the working volume is empty (steps 3-5). Every level
  // places at least its outermost filled cells, so this terminates after ~log2(size) levels.
  for (int level = 1; std::any_of(next.begin(), next.end(), [](uint16_t v) { return v != 0; }); ++level) {
    const std::vector<uint16_t> cur = std::move(next);
    dims = nextDims;
    next = scanLevel(GridView<uint16_t>{dims, cur.data()}, dim, level, kind, volume.hasLabels(), out, nextDims);
  }
  return out;
}

/// The model's vertex set as a bitmap over the lattice [0, nx] x [0, ny] x [0, nz] (x fastest,
/// z slowest, so bit order is the numbering order), plus the number of set bits before each
/// 64-bit word: a vertex's id is its rank, found in O(1) with one popcount. Cost is 1.5 bits per
/// lattice point (0.19 bytes; the input volume takes 1 byte per voxel) instead of 4 bytes for a
/// dense int32 index grid, and a lookup of an absent point (most closure queries) is one bit test.
class VertexSet {
 public:
  VertexSet(const std::array<int, 3>& dims, int dim)
      : sx_(uint64_t(dims[0]) + 1), sy_(uint64_t(dims[1]) + 1),
        bits_((sx_ * sy_ * (dim == 3 ? uint64_t(dims[2]) + 1 : 1) + 63) / 64, 0) {}

  uint64_t key(int x, int y, int z) const { return (uint64_t(z) * sy_ + uint64_t(y)) * sx_ + uint64_t(x); }
  Int3 point(uint64_t key) const {
    const uint64_t row = key / sx_;
    return Int3(int32_t(key % sx_), int32_t(row % sy_), int32_t(row / sy_));
  }
  void insert(uint64_t key) { bits_[key >> 6] |= uint64_t(1) << (key & 63); }
  /// Number of vertices inserted.
  uint64_t count() const {
    uint64_t n = 0;
    for (uint64_t w : bits_) n += uint64_t(std::popcount(w));
    return n;
  }

  /// Freezes the set: computes the rank table and returns the vertices in id order.
  std::vector<Int3> finish() {
    std::vector<Int3> points;
    before_.resize(bits_.size());
    uint32_t count = 0;
    for (size_t w = 0; w < bits_.size(); ++w) {
      before_[w] = count;
      if (uint64_t(count) + uint64_t(std::popcount(bits_[w])) > UINT32_MAX)
        throw InputError("layout: more than 2^32 vertices");
      count += uint32_t(std::popcount(bits_[w]));
      for (uint64_t m = bits_[w]; m; m &= m - 1)
        points.push_back(point(uint64_t(w) * 64 + uint64_t(std::countr_zero(m))));
    }
    return points;
  }
  /// Calls f(id) for every vertex with a key in [k0, k1], in ascending order. Only after finish().
  template <class F>
  void forEachIn(uint64_t k0, uint64_t k1, F&& f) const {
    for (uint64_t w = k0 >> 6, last = k1 >> 6; w <= last; ++w) {
      uint64_t m = bits_[w];
      if (w == k0 >> 6) m &= ~uint64_t(0) << (k0 & 63);
      if (w == last && (k1 & 63) != 63) m &= (uint64_t(1) << ((k1 & 63) + 1)) - 1;
      if (!m) continue;
      // The set bits of m are consecutive vertices: the first one's rank, then one more each.
      uint32_t id = before_[w] + uint32_t(std::popcount(bits_[w] & ((uint64_t(1) << std::countr_zero(m)) - 1)));
      for (; m; m &= m - 1, ++id) f(id);
    }
  }
  /// Vertex id at `key`, or -1 when no element owns a vertex there. Only after finish().
  int64_t find(uint64_t key) const {
    const uint64_t word = bits_[key >> 6], bit = uint64_t(1) << (key & 63);
    if (!(word & bit)) return -1;
    return int64_t(before_[key >> 6]) + std::popcount(word & (bit - 1));
  }

 private:
  uint64_t sx_, sy_;              // lattice points per row (nx + 1) and per column (ny + 1)
  std::vector<uint64_t> bits_;    // bit `key` set iff a vertex sits there
  std::vector<uint32_t> before_;  // set bits in the words before this one
};

/// Calls f(low, edge, c) for every cube [low, low + edge] making up element e's region: a full
/// element is one cube, its block (edge 2 * cellSize); an incomplete one is its filled cells c.
/// The own vertices (sec. 3.1, fig. 6) are exactly the corners of these cubes.
template <class F>
void forEachCube(const Placed& e, int dim, F&& f) {
  const bool full = e.mask == fullMask(dim);
  for (int c = 0; c < cellCount(dim); ++c) {
    if (!(e.mask & (1u << c)) || (full && c != 0)) continue;
    Int3 low = e.origin;
    for (int b = 0; b < dim; ++b) low[b] += cellCoord(c, b) * e.cellSize;
    f(low, full ? 2 * e.cellSize : e.cellSize, c);
  }
}

/// Calls f(low, edge, ax, side) for every boundary face of element e's region: the closed face
/// on axis `ax`, side `side` (0 = low, 1 = high), of a cube of forEachCube. Faces shared by two
/// filled cells of an incomplete block are interior and skipped.
template <class F>
void forEachBoundaryFace(const Placed& e, int dim, F&& f) {
  const bool full = e.mask == fullMask(dim);
  forEachCube(e, dim, [&](const Int3& low, int edge, int c) {
    for (int ax = 0; ax < dim; ++ax)
      for (int side = 0; side < 2; ++side) {
        const bool neighbourInBlock = !full && cellCoord(c, ax) != side;
        if (neighbourInBlock && (e.mask & (1u << (c ^ (1 << ax))))) continue;
        f(low, edge, ax, side);
      }
  });
}

/// Own vertex test (sec. 3.1, fig. 6): is p a corner of the block (full element) or of one of
/// the filled cells (incomplete element)?
bool isOwnCorner(const Int3& p, const Placed& e, int dim) {
  const int shift = std::countr_zero(unsigned(e.cellSize));  // cellSize is a power of two
  Int3 a(0, 0, 0);                                           // corner index within the block, 0..2 per axis
  for (int b = 0; b < dim; ++b) {
    const int rel = p[b] - e.origin[b];
    if (rel & (e.cellSize - 1)) return false;
    a[b] = rel >> shift;
    if (a[b] < 0 || a[b] > 2) return false;
    if (e.mask == fullMask(dim) && a[b] == 1) return false;  // a full element owns only block corners
  }
  if (e.mask == fullMask(dim)) return true;  // a block corner: a corner of a (filled) cell
  for (int c = 0; c < cellCount(dim); ++c) {
    if (!(e.mask & (1u << c))) continue;
    bool corner = true;
    for (int b = 0; b < dim; ++b) corner = corner && (a[b] == cellCoord(c, b) || a[b] == cellCoord(c, b) + 1);
    if (corner) return true;
  }
  return false;
}

}  // namespace

LayoutKind parseLayoutKind(const std::string& name) {
  if (name == "gradational") return LayoutKind::Gradational;
  if (name == "uniform") return LayoutKind::Uniform;
  if (name == "voxel") return LayoutKind::Voxel;
  throw InputError("", "layout", "unknown layout '" + name + "' (expected gradational, uniform or voxel)");
}

const char* layoutKindName(LayoutKind k) {
  switch (k) {
    case LayoutKind::Gradational: return "gradational";
    case LayoutKind::Uniform: return "uniform";
    case LayoutKind::Voxel: return "voxel";
  }
  return "unknown";
}

int Layout::numLevels() const {
  int top = -1;
  for (uint8_t l : level) top = std::max(top, int(l));
  return top + 1;
}

void Layout::indexVertices() {
  const size_t ny1 = size_t(dims[1]) + 1, rows = ny1 * (size_t(dims[2]) + 1);
  rowStart.assign(rows + 1, 0);
  for (const Int3& v : vertices) {
    if (v.y() < 0 || v.z() < 0 || v.y() > dims[1] || v.z() > dims[2])
      throw std::logic_error("Layout::indexVertices: a vertex outside the lattice");
    ++rowStart[size_t(v.z()) * ny1 + size_t(v.y()) + 1];
  }
  for (size_t r = 0; r < rows; ++r) rowStart[r + 1] += rowStart[r];
}

uint32_t Layout::vertexAt(const Int3& p) const {
  const size_t ny1 = size_t(dims[1]) + 1, rows = ny1 * (size_t(dims[2]) + 1);
  if (rowStart.size() == rows + 1 && rowStart.back() == vertices.size()) {
    if (p.y() < 0 || p.z() < 0 || p.y() > dims[1] || p.z() > dims[2]) return kNoVertex;
    const size_t row = size_t(p.z()) * ny1 + size_t(p.y());
    const auto b = vertices.begin() + rowStart[row], e = vertices.begin() + rowStart[row + 1];
    const auto it = std::lower_bound(b, e, p.x(), [](const Int3& a, int x) { return a.x() < x; });
    return it != e && it->x() == p.x() ? uint32_t(it - vertices.begin()) : kNoVertex;
  }
  auto before = [](const Int3& a, const Int3& b) {
    if (a.z() != b.z()) return a.z() < b.z();
    if (a.y() != b.y()) return a.y() < b.y();
    return a.x() < b.x();
  };
  const auto it = std::lower_bound(vertices.begin(), vertices.end(), p, before);
  return it != vertices.end() && *it == p ? uint32_t(it - vertices.begin()) : kNoVertex;
}

int64_t Layout::regionVoxels(size_t e) const {
  int64_t cellVolume = 1;
  for (int b = 0; b < dim; ++b) cellVolume *= cellSize[e];
  return int64_t(std::popcount(unsigned(cellMask[e]))) * cellVolume;
}

namespace {
/// The voxel layout's vertex set: every corner of a filled voxel.
VertexSet voxelCorners(const VoxelVolume& volume) {
  const int dim = volume.dim();
  VertexSet set(volume.dims(), dim);
  for (int k = 0; k < volume.nz(); ++k)
    for (int j = 0; j < volume.ny(); ++j)
      for (int i = 0; i < volume.nx(); ++i)
        if (volume.at(i, j, k))
          for (int corner = 0; corner < cellCount(dim); ++corner)
            set.insert(
                set.key(i + cellCoord(corner, 0), j + cellCoord(corner, 1), dim == 3 ? k + cellCoord(corner, 2) : 0));
  return set;
}
}  // namespace

LayoutCounts countLayout(const VoxelVolume& volume, LayoutKind kind) {
  if (volume.size() == 0 || volume.countFilled() == 0) throw InputError("layout: the volume is empty");
  const int dim = volume.dim();
  const uint64_t cells = uint64_t(cellCount(dim)), lattice = dim == 3 ? 27 : 9;
  LayoutCounts c;
  if (kind == LayoutKind::Voxel) {
    c.elements = volume.countFilled();
    c.vertices = voxelCorners(volume).count();
    c.pairsEstimate = cells * c.elements;  // a voxel element's boundary holds only its corners
    return c;
  }
  const std::vector<Placed> placed = place(volume, kind);
  VertexSet set(volume.dims(), dim);
  for (const Placed& e : placed)
    forEachCube(e, dim, [&](const Int3& low, int edge, int) {
      for (int corner = 0; corner < cellCount(dim); ++corner) {
        Int3 p = low;
        for (int b = 0; b < dim; ++b) p[b] += cellCoord(corner, b) * edge;
        set.insert(set.key(p.x(), p.y(), p.z()));
      }
    });
  c.elements = placed.size();
  c.vertices = set.count();
  // An element's own and hanging vertices are, next to neighbours at most one level finer, among
  // the 3^dim lattice points of its block at half its cell size (measured: 11 per element for a
  // gradational 128^3 box).
  c.pairsEstimate = lattice * c.elements;
  return c;
}

LayoutStats voxelLayoutStats(const VoxelVolume& volume) {
  LayoutStats s;
  s.voxels = volume.countFilled();
  if (s.voxels == 0) throw InputError("layout: the volume is empty");
  s.elements = s.voxels;
  s.elementsPerLevel = {s.voxels};
  s.uniqueVertices = voxelCorners(volume).count();
  s.pairs = size_t(cellCount(volume.dim())) * s.voxels;
  return s;
}

Layout buildLayout(const VoxelVolume& volume, LayoutKind kind) {
  if (volume.size() == 0 || volume.countFilled() == 0) throw InputError("layout: the volume is empty");
  const int dim = volume.dim();
  const int cells = cellCount(dim);
  const std::vector<Placed> placed = place(volume, kind);

  Layout L;
  L.dim = dim;
  L.dims = volume.dims();
  L.voxelSize = volume.voxelSize();
  L.kind = kind;

  // ---- vertices: union of own vertices, numbered in (z, y, x) order. Own vertices are the block
  // corners of a full element and the corners of the filled cells of an incomplete one (fig. 6),
  // i.e. the corners of the cubes of forEachCube. They all lie in [0, dims] because a
  // filled cell holds only filled voxels.
  VertexSet set(L.dims, dim);
  for (const Placed& e : placed)
    forEachCube(e, dim, [&](const Int3& low, int edge, int) {
      for (int corner = 0; corner < cells; ++corner) {
        Int3 p = low;
        for (int b = 0; b < dim; ++b) p[b] += cellCoord(corner, b) * edge;
        set.insert(set.key(p.x(), p.y(), p.z()));
      }
    });
  L.vertices = set.finish();
  L.indexVertices();

  // ---- closure (fig. 5): every model vertex on the region's boundary joins the element.
  // Only boundary faces are walked: a model vertex cannot lie in the interior of a region
  // because it is the corner of some other filled cell, whose interior would then overlap
  // this region, and regions are disjoint. Every own corner is on a boundary face too
  // (a block corner is on the block surface; the block centre, when not full, is on a face
  // between a filled and an empty cell), so the walk finds the own vertices as well.
  L.level.reserve(placed.size());
  L.cellSize.reserve(placed.size());
  L.origin.reserve(placed.size());
  L.cellMask.reserve(placed.size());
  L.label.reserve(placed.size());
  L.elemStart.reserve(placed.size() + 1);
  L.elemStart.push_back(0);
  L.elemVerts.reserve(placed.size() * size_t(cells));
  L.pairIsOwn.reserve(placed.size() * size_t(cells));
  std::vector<uint32_t> found;
  for (const Placed& e : placed) {
    found.clear();
    if (e.mask == fullMask(dim)) {
      // A full element's region is its block: the lattice points on the block's surface, row by
      // row in (z, y, x) order, i.e. ascending ids (no sort): whole rows on the faces z = lo, hi
      // and y = lo, hi, the two ends x = lo, hi of the other rows.
      const int edge = 2 * e.cellSize;
      const Int3 lo = e.origin;
      const int zHi = dim == 3 ? lo.z() + edge : lo.z();
      for (int z = lo.z(); z <= zHi; ++z)
        for (int y = lo.y(); y <= lo.y() + edge; ++y) {
          const uint64_t k0 = set.key(lo.x(), y, z), k1 = k0 + uint64_t(edge);
          if ((dim == 3 && (z == lo.z() || z == zHi)) || y == lo.y() || y == lo.y() + edge) {
            set.forEachIn(k0, k1, [&](uint32_t id) { found.push_back(id); });
          } else {
            if (const int64_t id = set.find(k0); id >= 0) found.push_back(uint32_t(id));
            if (const int64_t id = set.find(k1); id >= 0) found.push_back(uint32_t(id));
          }
        }
    } else {
      forEachBoundaryFace(e, dim, [&](const Int3& low, int edge, int ax, int side) {
        int lo[3], hi[3];  // closed lattice box of the face
        for (int b = 0; b < 3; ++b) {
          lo[b] = low[b];
          hi[b] = b < dim ? low[b] + edge : low[b];
        }
        lo[ax] = hi[ax] = low[ax] + side * edge;
        for (int z = lo[2]; z <= hi[2]; ++z)
          for (int y = lo[1]; y <= hi[1]; ++y)
            for (int x = lo[0]; x <= hi[0]; ++x) {
              const int64_t id = set.find(set.key(x, y, z));
              if (id >= 0) found.push_back(uint32_t(id));
            }
      });
      std::sort(found.begin(), found.end());
      found.erase(std::unique(found.begin(), found.end()), found.end());
    }
    // Ids and pair offsets are 32-bit (layout.h); only a voxel layout of ~1000^3 gets there.
    if (L.elemVerts.size() + found.size() > UINT32_MAX)
      throw InputError("layout: more than 2^32 element-vertex pairs; use a coarser layout or volume");
    for (uint32_t v : found) {
      L.elemVerts.push_back(v);
      L.pairIsOwn.push_back(isOwnCorner(L.vertices[v], e, dim) ? 1 : 0);
    }
    L.elemStart.push_back(uint32_t(L.elemVerts.size()));
    L.level.push_back(e.level);
    L.cellSize.push_back(e.cellSize);
    L.origin.push_back(e.origin);
    L.cellMask.push_back(e.mask);
    L.label.push_back(e.label);
  }
  return L;
}

LayoutStats layoutStats(const Layout& layout, const VoxelVolume& volume) {
  LayoutStats s;
  s.voxels = volume.countFilled();
  s.elements = layout.numElements();
  s.elementsPerLevel.assign(size_t(layout.numLevels()), 0);
  for (uint8_t l : layout.level) ++s.elementsPerLevel[l];
  s.uniqueVertices = layout.numVertices();
  s.pairs = layout.numPairs();
  std::vector<uint8_t> hanging(layout.numVertices(), 0);
  for (size_t p = 0; p < layout.numPairs(); ++p)
    if (!layout.pairIsOwn[p]) {
      ++s.hangingPairs;
      hanging[layout.elemVerts[p]] = 1;
    }
  s.hangingVertices = size_t(std::count(hanging.begin(), hanging.end(), uint8_t(1)));
  return s;
}

}  // namespace gradel
