// Tests for the layout builder (src/layout.cpp, paper sec. 3.1-3.2).
//
// Two kinds of test:
//   * exact counts on small shapes worked out by hand (the reasoning is in each test's comment);
//   * invariants checked by brute force on many shapes (spheres, odd boxes, seeded random
//     volumes, rapidcheck-generated volumes) for all three layout kinds: structure and numbering,
//     exact cover of the filled voxels, crack-free closure, and connectivity.
// The invariant checkers return "" or a description of the first violation, so the same checker
// serves EXPECT_EQ and RC_ASSERT.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <bit>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <tuple>

#include "gradel/layout.h"
#include "gradel/shapes.h"

namespace gradel {
namespace {

// ---------------------------------------------------------------------------------------------
// Shape helpers
// ---------------------------------------------------------------------------------------------

VoxelVolume filledBox(int dim, int nx, int ny, int nz) {
  VoxelVolume v(dim, nx, ny, nz, 0.01);
  std::fill(v.data().begin(), v.data().end(), uint8_t(1));
  return v;
}

/// A 2D volume from text rows: rows[j][i] == '#' fills voxel (i, j). Row 0 is y = 0.
VoxelVolume fromRows(const std::vector<std::string>& rows) {
  VoxelVolume v(2, int(rows[0].size()), int(rows.size()), 1, 0.01);
  for (int j = 0; j < int(rows.size()); ++j)
    for (int i = 0; i < int(rows[j].size()); ++i) v.set(i, j, 0, rows[j][i] == '#');
  return v;
}

VoxelVolume sphere(int size, int dim) { return rasterize(presetShape("sphere", size, dim)); }

/// Seeded random volume with fill probability p; never empty (voxel 0 is forced on if needed).
VoxelVolume randomVolume(int dim, int nx, int ny, int nz, double p, uint32_t seed) {
  VoxelVolume v(dim, nx, ny, nz, 0.01);
  std::mt19937 rng(seed);
  std::bernoulli_distribution fill(p);
  for (auto& c : v.data()) c = fill(rng) ? 1 : 0;
  if (v.countFilled() == 0) v.data()[0] = 1;
  return v;
}

// ---------------------------------------------------------------------------------------------
// Independent geometry of an element (written from the spec, not from src/layout.cpp)
// ---------------------------------------------------------------------------------------------

int cellsOf(int dim) { return dim == 3 ? 8 : 4; }

/// Lower corner [voxels] of cell c of element e.
Int3 cellLow(const Layout& L, size_t e, int c) {
  Int3 p = L.origin[e];
  for (int b = 0; b < L.dim; ++b) p[b] += ((c >> b) & 1) * L.cellSize[e];
  return p;
}

/// Is lattice point p in the closed region (union of closed filled cells) of element e?
bool inClosedRegion(const Layout& L, size_t e, const Int3& p) {
  for (int c = 0; c < cellsOf(L.dim); ++c) {
    if (!(L.cellMask[e] & (1u << c))) continue;
    const Int3 lo = cellLow(L, e, c);
    bool in = true;
    for (int b = 0; b < L.dim; ++b) in = in && p[b] >= lo[b] && p[b] <= lo[b] + L.cellSize[e];
    if (in) return true;
  }
  return false;
}

/// Own vertices by the spec: the block corners of a full element, the corners of the filled
/// cells of an incomplete one.
std::set<std::tuple<int, int, int>> ownCorners(const Layout& L, size_t e) {
  std::set<std::tuple<int, int, int>> out;
  if (L.isFull(e)) {
    for (int k = 0; k < cellsOf(L.dim); ++k) {
      Int3 p = L.origin[e];
      for (int b = 0; b < L.dim; ++b) p[b] += ((k >> b) & 1) * 2 * L.cellSize[e];
      out.insert({p.x(), p.y(), p.z()});
    }
    return out;
  }
  for (int c = 0; c < cellsOf(L.dim); ++c) {
    if (!(L.cellMask[e] & (1u << c))) continue;
    const Int3 lo = cellLow(L, e, c);
    for (int k = 0; k < cellsOf(L.dim); ++k) {
      Int3 p = lo;
      for (int b = 0; b < L.dim; ++b) p[b] += ((k >> b) & 1) * L.cellSize[e];
      out.insert({p.x(), p.y(), p.z()});
    }
  }
  return out;
}

std::tuple<int, int, int> zyx(const Int3& p) { return {p.z(), p.y(), p.x()}; }

std::vector<std::tuple<int, int, int>> elementVertices(const Layout& L, size_t e) {
  std::vector<std::tuple<int, int, int>> out;
  for (uint32_t p = L.elemStart[e]; p < L.elemStart[e + 1]; ++p) {
    const Int3& v = L.vertices[L.elemVerts[p]];
    out.push_back({v.x(), v.y(), v.z()});
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Invariant checkers: "" when the property holds, else the first violation.
// ---------------------------------------------------------------------------------------------

#define LAYOUT_REQUIRE(cond, what) \
  do {                             \
    if (!(cond)) {                 \
      std::ostringstream os_;      \
      os_ << what;                 \
      return os_.str();            \
    }                              \
  } while (0)

/// Element fields, alignment, and the numbering rules of layout.h.
std::string checkStructure(const Layout& L, const VoxelVolume& vol) {
  const size_t E = L.numElements();
  LAYOUT_REQUIRE(L.dim == vol.dim() && L.dims == vol.dims(), "dims differ from the volume");
  LAYOUT_REQUIRE(L.cellSize.size() == E && L.origin.size() == E && L.cellMask.size() == E,
                 "element arrays differ in size");
  LAYOUT_REQUIRE(L.elemStart.size() == E + 1 && L.elemStart[0] == 0 && L.elemStart[E] == L.numPairs(),
                 "elemStart malformed");
  LAYOUT_REQUIRE(L.pairIsOwn.size() == L.numPairs(), "pairIsOwn size");
  const unsigned full = L.dim == 3 ? 0xFFu : 0x0Fu;
  for (size_t e = 0; e < E; ++e) {
    const int cs = L.cellSize[e];
    LAYOUT_REQUIRE(L.cellMask[e] != 0, "element " << e << " has an empty mask");
    LAYOUT_REQUIRE((L.cellMask[e] & ~full) == 0, "element " << e << " has cells outside the block");
    LAYOUT_REQUIRE(cs == (L.kind == LayoutKind::Voxel ? 1 : (1 << L.level[e])), "element " << e << " cell size");
    if (L.kind != LayoutKind::Gradational) LAYOUT_REQUIRE(L.level[e] == 0, "non-gradational level > 0");
    if (L.kind == LayoutKind::Voxel)
      LAYOUT_REQUIRE(std::popcount(unsigned(L.cellMask[e])) == 1, "voxel element with >1 cell");
    for (int b = 0; b < 3; ++b) LAYOUT_REQUIRE(L.origin[e][b] >= 0, "negative origin");
    for (int b = 0; b < L.dim; ++b)
      LAYOUT_REQUIRE(L.origin[e][b] % (2 * cs) == 0, "element " << e << " origin not aligned");
    if (L.dim == 2) LAYOUT_REQUIRE(L.origin[e].z() == 0, "2D element with z != 0");
    LAYOUT_REQUIRE(L.elemStart[e + 1] > L.elemStart[e], "element " << e << " has no vertices");
    for (uint32_t p = L.elemStart[e]; p < L.elemStart[e + 1]; ++p) {
      LAYOUT_REQUIRE(L.elemVerts[p] < L.numVertices(), "vertex id out of range");
      if (p > L.elemStart[e])
        LAYOUT_REQUIRE(L.elemVerts[p] > L.elemVerts[p - 1], "element " << e << " list not strictly sorted");
    }
    if (e > 0) {
      const auto prev =
          std::make_tuple(L.level[e - 1], zyx(L.origin[e - 1]), std::countr_zero(unsigned(L.cellMask[e - 1])));
      const auto cur = std::make_tuple(L.level[e], zyx(L.origin[e]), std::countr_zero(unsigned(L.cellMask[e])));
      LAYOUT_REQUIRE(prev < cur, "elements " << e - 1 << ", " << e << " out of order");
    }
  }
  for (size_t v = 0; v < L.numVertices(); ++v) {
    for (int b = 0; b < 3; ++b)
      LAYOUT_REQUIRE(L.vertices[v][b] >= 0 && L.vertices[v][b] <= L.dims[b], "vertex outside [0, dims]");
    if (L.dim == 2) LAYOUT_REQUIRE(L.vertices[v].z() == 0, "2D vertex with z != 0");
    if (v > 0) LAYOUT_REQUIRE(zyx(L.vertices[v - 1]) < zyx(L.vertices[v]), "vertices not strictly sorted by (z, y, x)");
  }
  return "";
}

/// Every filled voxel lies in exactly one element's region and regions hold only filled voxels.
std::string checkCoverage(const Layout& L, const VoxelVolume& vol) {
  std::vector<int> covered(vol.size(), 0);
  int64_t total = 0;
  for (size_t e = 0; e < L.numElements(); ++e) {
    total += L.regionVoxels(e);
    const int cs = L.cellSize[e];
    for (int c = 0; c < cellsOf(L.dim); ++c) {
      if (!(L.cellMask[e] & (1u << c))) continue;
      const Int3 lo = cellLow(L, e, c);
      for (int k = lo.z(); k < lo.z() + (L.dim == 3 ? cs : 1); ++k)
        for (int j = lo.y(); j < lo.y() + cs; ++j)
          for (int i = lo.x(); i < lo.x() + cs; ++i) {
            LAYOUT_REQUIRE(vol.at(i, j, k), "element " << e << " covers empty voxel " << i << "," << j << "," << k);
            ++covered[vol.index(i, j, k)];
          }
    }
  }
  LAYOUT_REQUIRE(total == int64_t(vol.countFilled()),
                 "region volume " << total << " != filled voxels " << vol.countFilled());
  for (size_t i = 0; i < covered.size(); ++i)
    LAYOUT_REQUIRE(covered[i] == (vol.data()[i] ? 1 : 0), "voxel index " << i << " covered " << covered[i] << " times");
  return "";
}

/// Crack-free closure (fig. 5): an element's list is exactly the model vertices in the closed
/// region of its filled cells; pairIsOwn marks exactly the own vertices; the model's vertex set
/// is exactly the union of own vertices. Brute force over every lattice point of each closed
/// block (interior included), through a dense lattice -> vertex id table.
std::string checkClosure(const Layout& L) {
  const int sx = L.dims[0] + 1, sy = L.dims[1] + 1, sz = L.dim == 3 ? L.dims[2] + 1 : 1;
  auto lattice = [&](int x, int y, int z) { return size_t(x) + size_t(sx) * (size_t(y) + size_t(sy) * size_t(z)); };
  std::vector<int64_t> idAt(size_t(sx) * size_t(sy) * size_t(sz), -1);
  std::set<std::tuple<int, int, int>> allVerts, unionOwn;
  for (size_t v = 0; v < L.numVertices(); ++v) {
    const Int3& p = L.vertices[v];
    idAt[lattice(p.x(), p.y(), p.z())] = int64_t(v);
    allVerts.insert({p.x(), p.y(), p.z()});
  }
  for (size_t e = 0; e < L.numElements(); ++e) {
    const auto own = ownCorners(L, e);
    unionOwn.insert(own.begin(), own.end());
    int hi[3];
    for (int b = 0; b < 3; ++b) hi[b] = b < L.dim ? std::min(L.origin[e][b] + 2 * L.cellSize[e], L.dims[b]) : 0;
    std::vector<uint32_t> expected;
    for (int z = L.origin[e].z(); z <= hi[2]; ++z)
      for (int y = L.origin[e].y(); y <= hi[1]; ++y)
        for (int x = L.origin[e].x(); x <= hi[0]; ++x) {
          const int64_t id = idAt[lattice(x, y, z)];
          if (id >= 0 && inClosedRegion(L, e, Int3(x, y, z))) expected.push_back(uint32_t(id));
        }
    std::sort(expected.begin(), expected.end());
    const std::vector<uint32_t> actual(L.elemVerts.begin() + L.elemStart[e], L.elemVerts.begin() + L.elemStart[e + 1]);
    LAYOUT_REQUIRE(actual == expected, "element " << e << " has " << actual.size()
                                                  << " vertices, the closed region holds " << expected.size());
    for (uint32_t p = L.elemStart[e]; p < L.elemStart[e + 1]; ++p) {
      const Int3& v = L.vertices[L.elemVerts[p]];
      LAYOUT_REQUIRE(bool(L.pairIsOwn[p]) == (own.count({v.x(), v.y(), v.z()}) > 0),
                     "element " << e << " wrong pairIsOwn");
    }
  }
  LAYOUT_REQUIRE(allVerts == unionOwn, "vertex set != union of own corners");
  return "";
}

/// Components of the element graph (elements sharing a vertex) == vertex-connected (26 in 3D,
/// 8 in 2D) components of the filled voxels.
std::string checkConnectivity(const Layout& L, const VoxelVolume& vol) {
  std::vector<size_t> parent(L.numElements());
  std::iota(parent.begin(), parent.end(), size_t(0));
  auto find = [&](size_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  std::vector<int64_t> firstElem(L.numVertices(), -1);
  for (size_t e = 0; e < L.numElements(); ++e)
    for (uint32_t p = L.elemStart[e]; p < L.elemStart[e + 1]; ++p) {
      int64_t& f = firstElem[L.elemVerts[p]];
      if (f < 0)
        f = int64_t(e);
      else
        parent[find(e)] = find(size_t(f));
    }
  size_t elementComponents = 0;
  for (size_t e = 0; e < L.numElements(); ++e) elementComponents += find(e) == e;

  std::vector<uint8_t> seen(vol.size(), 0);
  size_t voxelComponents = 0;
  const int dz = vol.dim() == 3 ? 1 : 0;
  for (int k = 0; k < vol.nz(); ++k)
    for (int j = 0; j < vol.ny(); ++j)
      for (int i = 0; i < vol.nx(); ++i) {
        if (!vol.at(i, j, k) || seen[vol.index(i, j, k)]) continue;
        ++voxelComponents;
        std::vector<Int3> stack{Int3(i, j, k)};
        seen[vol.index(i, j, k)] = 1;
        while (!stack.empty()) {
          const Int3 q = stack.back();
          stack.pop_back();
          for (int c = -dz; c <= dz; ++c)
            for (int b = -1; b <= 1; ++b)
              for (int a = -1; a <= 1; ++a) {
                const Int3 r = q + Int3(a, b, c);
                if (vol.at(r.x(), r.y(), r.z()) && !seen[vol.index(r.x(), r.y(), r.z())]) {
                  seen[vol.index(r.x(), r.y(), r.z())] = 1;
                  stack.push_back(r);
                }
              }
        }
      }
  LAYOUT_REQUIRE(elementComponents == voxelComponents,
                 elementComponents << " element components vs " << voxelComponents << " voxel components");
  return "";
}

/// All checks, stopping at the first failure (later checkers assume the earlier properties).
std::string checkAll(const Layout& L, const VoxelVolume& vol) {
  std::string s = checkStructure(L, vol);
  if (s.empty()) s = checkCoverage(L, vol);
  if (s.empty()) s = checkClosure(L);
  if (s.empty()) s = checkConnectivity(L, vol);
  return s.empty() ? s : std::string(layoutKindName(L.kind)) + ": " + s;
}

constexpr LayoutKind kAllKinds[] = {LayoutKind::Gradational, LayoutKind::Uniform, LayoutKind::Voxel};

size_t hangingPairs(const Layout& L) { return size_t(std::count(L.pairIsOwn.begin(), L.pairIsOwn.end(), uint8_t(0))); }

// ---------------------------------------------------------------------------------------------
// Names and errors
// ---------------------------------------------------------------------------------------------

TEST(LayoutKind, ParseAndNameRoundTrip) {
  for (LayoutKind k : kAllKinds) EXPECT_EQ(parseLayoutKind(layoutKindName(k)), k);
  EXPECT_STREQ(layoutKindName(LayoutKind::Gradational), "gradational");
  EXPECT_THROW(parseLayoutKind("octree"), InputError);
  EXPECT_THROW(parseLayoutKind(""), InputError);
}

TEST(Layout, EmptyVolumeThrowsInputError) {
  for (LayoutKind k : kAllKinds) {
    EXPECT_THROW(buildLayout(VoxelVolume(3, 4, 4, 4, 0.01), k), InputError);
    EXPECT_THROW(buildLayout(VoxelVolume(2, 5, 3, 1, 0.01), k), InputError);
  }
  try {
    buildLayout(VoxelVolume(3, 2, 2, 2, 0.01), LayoutKind::Gradational);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "layout: the volume is empty");
  }
}

// ---------------------------------------------------------------------------------------------
// Hand-counted shapes
// ---------------------------------------------------------------------------------------------

TEST(Layout, FullBox2x2x2IsOneElement) {
  // One full group at level 0; its cells are all on the grid border, so it gets an element.
  // The 8 block corners are its vertices; nothing else exists to hang.
  for (LayoutKind k : {LayoutKind::Gradational, LayoutKind::Uniform}) {
    const Layout L = buildLayout(filledBox(3, 2, 2, 2), k);
    ASSERT_EQ(L.numElements(), 1u);
    EXPECT_TRUE(L.isFull(0));
    EXPECT_EQ(L.cellSize[0], 1);
    EXPECT_EQ(L.numVertices(), 8u);
    EXPECT_EQ(L.numPairs(), 8u);
    EXPECT_EQ(L.vertices.front(), Int3(0, 0, 0));
    EXPECT_EQ(L.vertices.back(), Int3(2, 2, 2));
  }
}

TEST(Layout, Box4x4x4Gradational) {
  // 8 level-0 groups, each holding a grid-border cell -> 8 full elements of 2^3 voxels; level 1
  // is then empty. Vertices: the even lattice {0,2,4}^3 = 27; 8 x 8 = 64 pairs; every element
  // only meets the others at shared corners, so nothing hangs.
  const VoxelVolume vol = filledBox(3, 4, 4, 4);
  const Layout L = buildLayout(vol, LayoutKind::Gradational);
  EXPECT_EQ(L.numElements(), 8u);
  EXPECT_EQ(L.numLevels(), 1);
  EXPECT_EQ(L.numVertices(), 27u);
  EXPECT_EQ(L.numPairs(), 64u);
  EXPECT_EQ(hangingPairs(L), 0u);
  for (size_t e = 0; e < L.numElements(); ++e) EXPECT_TRUE(L.isFull(e));
  EXPECT_EQ(checkAll(L, vol), "");
}

TEST(Layout, Box4x4x4VoxelAndUniform) {
  const VoxelVolume vol = filledBox(3, 4, 4, 4);
  // Voxel layout: one element per voxel (64), the full lattice 5^3 = 125 vertices, 64 x 8 pairs.
  const Layout V = buildLayout(vol, LayoutKind::Voxel);
  EXPECT_EQ(V.numElements(), 64u);
  EXPECT_EQ(V.numVertices(), 125u);
  EXPECT_EQ(V.numPairs(), 512u);
  EXPECT_EQ(hangingPairs(V), 0u);
  // Block origin is the even-aligned 2x2x2 voxel group; mask is that voxel's bit. Elements 0-7
  // are the 8 voxels of the block at the origin, in cell order.
  for (int c = 0; c < 8; ++c) {
    EXPECT_EQ(V.origin[size_t(c)], Int3(0, 0, 0));
    EXPECT_EQ(V.cellMask[size_t(c)], 1u << c);
  }
  // Uniform layout on a full box equals the gradational one at level 0.
  const Layout U = buildLayout(vol, LayoutKind::Uniform);
  EXPECT_EQ(U.numElements(), 8u);
  EXPECT_EQ(U.numVertices(), 27u);
  EXPECT_EQ(U.numPairs(), 64u);
  EXPECT_EQ(checkAll(V, vol), "");
  EXPECT_EQ(checkAll(U, vol), "");
}

TEST(Layout, Square8x8In2DGradational) {
  // Level 0 (8x8 cells, 4x4 groups): the ring of 12 groups holds border cells -> 12 full
  // elements of 2x2 voxels. The 4 centre groups (voxels 2..5) have no empty face neighbour.
  // Level 1 (4x4 cells of 2x2 voxels): only cells (1..2, 1..2) are filled. Groups are aligned
  // to multiples of 2 cells, so this 2x2-cell centre straddles all four level-1 groups: each
  // group holds exactly one filled cell -> 4 *incomplete* elements of one 2x2-voxel cell
  // (mask bits 3, 2, 1, 0 for groups (0,0), (1,0), (0,1), (1,1)). It is NOT one 4x4 element:
  // the aligned-group rule of sec. 3.2 never places a block across a group boundary.
  // Vertices: even lattice {0,2,4,6,8}^2 = 25 (the centre (4,4) comes from level 1).
  // Pairs 12*4 + 4*4 = 64. No vertex hangs: level-0 vertices are all even, and an edge of a
  // level-1 cell (length 2) holds no even point besides its ends.
  const VoxelVolume vol = filledBox(2, 8, 8, 1);
  const Layout L = buildLayout(vol, LayoutKind::Gradational);
  const LayoutStats s = layoutStats(L, vol);
  EXPECT_EQ(s.elementsPerLevel, (std::vector<size_t>{12, 4}));
  EXPECT_EQ(s.uniqueVertices, 25u);
  EXPECT_EQ(s.pairs, 64u);
  EXPECT_EQ(s.hangingVertices, 0u);
  const uint8_t expectedMask[4] = {8, 4, 2, 1};
  for (size_t e = 12; e < 16; ++e) {
    EXPECT_EQ(L.cellSize[e], 2);
    EXPECT_EQ(L.cellMask[e], expectedMask[e - 12]);
    EXPECT_EQ(L.regionVoxels(e), 4);
  }
  EXPECT_EQ(checkAll(L, vol), "");
}

TEST(Layout, Square12x12In2DHasHangingVertices) {
  // Level 0: 6x6 groups; the ring of 36 - 16 = 20 holds border cells -> 20 full elements.
  // Level 1: 6x6 cells, filled 1..4 (voxels 2..10); 3x3 groups. Corner groups hold 1 filled
  //   cell, edge groups 2, the centre group (cells 2..3 = voxels 4..8) is full and its cells'
  //   outward neighbours are filled -> 8 incomplete elements; the centre survives.
  // Level 2: 3x3 cells, only (1,1) = voxels [4,8]^2 filled; its group (0,0) is partial -> one
  //   incomplete element, cell edge 4. Its edges carry the level-1 corners (6,4), (4,6), (8,6),
  //   (6,8): 4 hanging vertices (fig. 5's asymmetric element).
  // Vertices: level 0 gives the even lattice {0..12}^2 = 49 minus the 9 points inside (2,10)^2;
  //   level 1 puts back all of those except (6,6) -> 48.
  // Pairs: 20*4 + (4 corner groups * 4 + 4 edge groups * 6) + (4 own + 4 hanging) = 128.
  const VoxelVolume vol = filledBox(2, 12, 12, 1);
  const Layout L = buildLayout(vol, LayoutKind::Gradational);
  const LayoutStats s = layoutStats(L, vol);
  EXPECT_EQ(s.elementsPerLevel, (std::vector<size_t>{20, 8, 1}));
  EXPECT_EQ(s.uniqueVertices, 48u);
  EXPECT_EQ(s.pairs, 128u);
  EXPECT_EQ(s.hangingVertices, 4u);
  EXPECT_EQ(s.hangingPairs, 4u);
  const size_t top = L.numElements() - 1;
  EXPECT_EQ(L.level[top], 2);
  EXPECT_EQ(L.cellSize[top], 4);
  EXPECT_EQ(L.origin[top], Int3(0, 0, 0));
  EXPECT_EQ(L.cellMask[top], 8u);  // cell (1,1)
  const std::vector<std::tuple<int, int, int>> expectedVerts = {{4, 4, 0}, {6, 4, 0}, {8, 4, 0}, {4, 6, 0},
                                                                {8, 6, 0}, {4, 8, 0}, {6, 8, 0}, {8, 8, 0}};
  EXPECT_EQ(elementVertices(L, top), expectedVerts);
  const std::vector<uint8_t> own(L.pairIsOwn.begin() + L.elemStart[top], L.pairIsOwn.end());
  EXPECT_EQ(own, (std::vector<uint8_t>{1, 0, 1, 0, 0, 1, 0, 1}));
  EXPECT_EQ(checkAll(L, vol), "");
}

TEST(Layout, Box12x12x12GradationalCounts) {
  // The 3D analogue of the 12x12 square.
  // Level 0: 6^3 - 4^3 = 152 full elements. Level 1: 27 groups minus the surviving centre = 26
  //   incomplete elements: 8 corner groups (1 cell, 8 vertices), 12 edge groups (2 cells, 12),
  //   6 face groups (4 cells, 18). Level 2: one incomplete element, the cube [4,8]^3 of cell edge
  //   4; every face carries 4 edge midpoints + 1 face centre from level 1: 12 + 6 = 18 hanging.
  // Vertices: even lattice 7^3 = 343, all present except the cube centre (6,6,6) -> 342.
  // Pairs: 152*8 + (8*8 + 12*12 + 6*18) + (8 + 18) = 1216 + 316 + 26 = 1558.
  const VoxelVolume vol = filledBox(3, 12, 12, 12);
  const Layout L = buildLayout(vol, LayoutKind::Gradational);
  const LayoutStats s = layoutStats(L, vol);
  EXPECT_EQ(s.elementsPerLevel, (std::vector<size_t>{152, 26, 1}));
  EXPECT_EQ(s.uniqueVertices, 342u);
  EXPECT_EQ(s.pairs, 1558u);
  EXPECT_EQ(s.hangingVertices, 18u);
  EXPECT_EQ(s.hangingPairs, 18u);
  EXPECT_EQ(L.elemStart.back() - L.elemStart[L.numElements() - 1], 26u);
  EXPECT_EQ(checkAll(L, vol), "");
}

TEST(Layout, OddSquare3x3In2DGivesIncompleteElements) {
  // Padded to 4x4, so 2x2 groups:
  //   (0,0): voxels (0..1, 0..1), full, on the border -> full element, corners (0,0),(2,0),(0,2),(2,2);
  //   (1,0): voxels (2,0),(2,1) + padding -> incomplete, mask 0b0101 = 5, 6 corners;
  //   (0,1): voxels (0,2),(1,2) -> incomplete, mask 0b0011 = 3, 6 corners;
  //   (1,1): voxel (2,2) -> incomplete, mask 1, 4 corners.
  // Union of corners: the 4x4 lattice minus (1,0), (0,1), (1,1) = 13 vertices.
  // The full element's edges x = 2 and y = 2 carry (2,1) and (1,2), the corners of the unit
  // cells next to it: 2 hanging vertices. Pairs: (4+2) + 6 + 6 + 4 = 22.
  const VoxelVolume vol = filledBox(2, 3, 3, 1);
  for (LayoutKind k : {LayoutKind::Gradational, LayoutKind::Uniform}) {
    const Layout L = buildLayout(vol, k);
    const LayoutStats s = layoutStats(L, vol);
    ASSERT_EQ(L.numElements(), 4u);
    EXPECT_EQ(std::vector<uint8_t>(L.cellMask.begin(), L.cellMask.end()), (std::vector<uint8_t>{15, 5, 3, 1}));
    EXPECT_TRUE(L.isFull(0));
    EXPECT_FALSE(L.isFull(1));
    EXPECT_EQ(s.uniqueVertices, 13u);
    EXPECT_EQ(s.pairs, 22u);
    EXPECT_EQ(s.hangingVertices, 2u);
    EXPECT_EQ(elementVertices(L, 0), (std::vector<std::tuple<int, int, int>>{
                                         {0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 2, 0}, {1, 2, 0}, {2, 2, 0}}));
    EXPECT_EQ(checkAll(L, vol), "");
  }
}

TEST(Layout, SingleVoxel) {
  // One filled voxel anywhere: one incomplete level-0 element with that voxel's bit, and its
  // 2^dim corners. Voxel (1,2,3) lies in the block at (0,2,2), cell (1,0,1) -> bit 1 + 4 = 5.
  VoxelVolume v3(3, 4, 4, 4, 0.01);
  v3.set(1, 2, 3, true);
  for (LayoutKind k : kAllKinds) {
    const Layout L = buildLayout(v3, k);
    ASSERT_EQ(L.numElements(), 1u);
    EXPECT_EQ(L.origin[0], Int3(0, 2, 2));
    EXPECT_EQ(L.cellMask[0], 1u << 5);
    EXPECT_EQ(L.numVertices(), 8u);
    EXPECT_EQ(L.numPairs(), 8u);
    EXPECT_EQ(L.vertices.front(), Int3(1, 2, 3));
    EXPECT_EQ(L.vertices.back(), Int3(2, 3, 4));
    EXPECT_EQ(L.regionVoxels(0), 1);
  }
  const VoxelVolume v2 = fromRows({"#"});
  const Layout L2 = buildLayout(v2, LayoutKind::Gradational);
  ASSERT_EQ(L2.numElements(), 1u);
  EXPECT_EQ(L2.cellMask[0], 1u);
  EXPECT_EQ(L2.numVertices(), 4u);
  EXPECT_EQ(checkAll(L2, v2), "");
}

TEST(Layout, LShape3x3In2D) {
  // Row 0 is y = 0:   ###
  //                   #..
  //                   #..
  // Group (0,0) holds (0,0),(1,0),(0,1) and the empty (1,1): incomplete, mask 0b0111 = 7,
  // corners (0..2,0), (0..2,1), (0,2), (1,2) = 8. Group (1,0) holds (2,0): mask 1, 4 corners,
  // 2 new ((3,0), (3,1)). Group (0,1) holds (0,2): mask 1, 4 corners, 2 new ((0,3), (1,3)).
  // Group (1,1) is empty. 12 vertices, 8 + 4 + 4 = 16 pairs; all neighbours share whole unit
  // edges, so nothing hangs.
  const VoxelVolume vol = fromRows({"###", "#..", "#.."});
  const Layout L = buildLayout(vol, LayoutKind::Gradational);
  ASSERT_EQ(L.numElements(), 3u);
  EXPECT_EQ(std::vector<uint8_t>(L.cellMask.begin(), L.cellMask.end()), (std::vector<uint8_t>{7, 1, 1}));
  EXPECT_EQ(L.numVertices(), 12u);
  EXPECT_EQ(L.numPairs(), 16u);
  EXPECT_EQ(hangingPairs(L), 0u);
  EXPECT_EQ(checkAll(L, vol), "");
}

TEST(Layout, LShape8x8In2DKeepsInnerCornerGroupForLevel1) {
  // 8x8 minus the 4x4 quadrant x >= 4, y >= 4. Level 0 groups (gx, gy) with gx < 2 or gy < 2:
  // 12 full groups. All but (1,1) touch the border or the notch: (2,1)'s cell (4,3) has the
  // empty (4,4) above it; (1,2)'s cell (3,4) has the empty (4,4) beside it. So 11 level-0
  // elements; (1,1) becomes level-1 cell (1,1), alone in its level-1 group -> 1 incomplete
  // element, cell edge 2. Vertices: even lattice 25 minus (6,6), (8,6), (6,8), (8,8) = 21.
  // Pairs 12 * 4 = 48, no hanging (as in the 8x8 square).
  const VoxelVolume vol =
      fromRows({"########", "########", "########", "########", "####....", "####....", "####....", "####...."});
  const Layout L = buildLayout(vol, LayoutKind::Gradational);
  const LayoutStats s = layoutStats(L, vol);
  EXPECT_EQ(s.elementsPerLevel, (std::vector<size_t>{11, 1}));
  EXPECT_EQ(s.uniqueVertices, 21u);
  EXPECT_EQ(s.pairs, 48u);
  EXPECT_EQ(s.hangingVertices, 0u);
  EXPECT_EQ(L.origin.back(), Int3(0, 0, 0));
  EXPECT_EQ(L.cellMask.back(), 8u);
  EXPECT_EQ(checkAll(L, vol), "");
}

TEST(Layout, SurfaceUsesFaceNeighboursOnly) {
  // 6x6 2D square with voxel (1,1) removed. Level 0: the 8 ring groups hold border cells (group
  // (0,0) is also partial) -> 8 elements. The centre group (voxels 2..3) is full; its cell (2,2)
  // touches the empty (1,1) only diagonally, so it is NOT a surface cell (face neighbours only)
  // and the group survives. Level 1: it is cell (1,1), alone in level-1 group (0,0) -> one
  // incomplete element, cell edge 2, mask bit 3.
  const VoxelVolume vol = fromRows({"######", "#.####", "######", "######", "######", "######"});
  const Layout L = buildLayout(vol, LayoutKind::Gradational);
  const LayoutStats s = layoutStats(L, vol);
  EXPECT_EQ(s.elementsPerLevel, (std::vector<size_t>{8, 1}));
  EXPECT_EQ(L.cellSize.back(), 2);
  EXPECT_EQ(L.origin.back(), Int3(0, 0, 0));
  EXPECT_EQ(L.cellMask.back(), 8u);
  EXPECT_EQ(checkAll(L, vol), "");
}

// ---------------------------------------------------------------------------------------------
// Invariants on many shapes
// ---------------------------------------------------------------------------------------------

TEST(Layout, InvariantsOnSpheres) {
  for (int dim : {2, 3})
    for (int n = 1; n <= 16; ++n) {
      if (dim == 3 && n > 14 && n != 16) continue;  // keep the brute force quick
      const VoxelVolume vol = sphere(n, dim);
      for (LayoutKind k : kAllKinds) EXPECT_EQ(checkAll(buildLayout(vol, k), vol), "") << "dim " << dim << " n " << n;
    }
}

TEST(Layout, InvariantsOnOddBoxes) {
  for (auto [nx, ny, nz] :
       {std::array<int, 3>{1, 1, 1}, {3, 5, 7}, {5, 5, 5}, {7, 3, 1}, {9, 9, 9}, {13, 11, 6}, {1, 17, 2}}) {
    const VoxelVolume v3 = filledBox(3, nx, ny, nz);
    for (LayoutKind k : kAllKinds) EXPECT_EQ(checkAll(buildLayout(v3, k), v3), "") << nx << "x" << ny << "x" << nz;
    const VoxelVolume v2 = filledBox(2, nx, ny, 1);
    for (LayoutKind k : kAllKinds) EXPECT_EQ(checkAll(buildLayout(v2, k), v2), "") << nx << "x" << ny;
  }
}

TEST(Layout, InvariantsOnSeededRandomVolumes) {
  // Dense random volumes reach level 2+ with holes and islands; sparse ones are many small
  // components.
  uint32_t seed = 1;
  for (double p : {0.3, 0.7, 0.9, 0.97})
    for (int rep = 0; rep < 6; ++rep, ++seed) {
      const VoxelVolume v3 = randomVolume(3, 6 + rep, 9 - rep, 7, p, seed);
      const VoxelVolume v2 = randomVolume(2, 13 + rep, 17 - rep, 1, p, seed);
      for (LayoutKind k : kAllKinds) {
        EXPECT_EQ(checkAll(buildLayout(v3, k), v3), "") << "seed " << seed;
        EXPECT_EQ(checkAll(buildLayout(v2, k), v2), "") << "seed " << seed;
      }
    }
}

RC_GTEST_PROP(LayoutProperty, RandomVolumesSatisfyAllInvariants, ()) {
  const int dim = *rc::gen::element(2, 3);
  const int nx = *rc::gen::inRange(1, 11);
  const int ny = *rc::gen::inRange(1, 11);
  const int nz = dim == 3 ? *rc::gen::inRange(1, 11) : 1;
  // Fill by a threshold on random bytes so that shrinking moves towards emptier volumes.
  const int threshold = *rc::gen::inRange(1, 256);
  const auto bytes =
      *rc::gen::container<std::vector<int>>(size_t(nx) * size_t(ny) * size_t(nz), rc::gen::inRange(0, 256));
  VoxelVolume vol(dim, nx, ny, nz, 0.01);
  for (size_t i = 0; i < bytes.size(); ++i) vol.data()[i] = bytes[i] < threshold ? 1 : 0;
  RC_PRE(vol.countFilled() > 0);
  const LayoutKind kind = kAllKinds[*rc::gen::inRange(0, 3)];  // checkAll's message names it
  RC_ASSERT(checkAll(buildLayout(vol, kind), vol) == std::string());
}

TEST(Layout, DeterministicAcrossBuilds) {
  const VoxelVolume vol = randomVolume(3, 10, 9, 8, 0.85, 42);
  const Layout a = buildLayout(vol, LayoutKind::Gradational);
  const Layout b = buildLayout(vol, LayoutKind::Gradational);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.elemVerts, b.elemVerts);
  EXPECT_EQ(a.pairIsOwn, b.pairIsOwn);
  EXPECT_EQ(a.origin, b.origin);
  EXPECT_EQ(a.cellMask, b.cellMask);
}

TEST(Layout, StatsAgreeWithLayout) {
  const VoxelVolume vol = sphere(14, 3);
  const Layout L = buildLayout(vol, LayoutKind::Gradational);
  const LayoutStats s = layoutStats(L, vol);
  EXPECT_EQ(s.voxels, vol.countFilled());
  EXPECT_EQ(s.elements, L.numElements());
  EXPECT_EQ(std::accumulate(s.elementsPerLevel.begin(), s.elementsPerLevel.end(), size_t(0)), L.numElements());
  EXPECT_EQ(s.elementsPerLevel.size(), size_t(L.numLevels()));
  EXPECT_EQ(s.pairs, L.numPairs());
  EXPECT_EQ(s.hangingPairs, hangingPairs(L));
  std::set<uint32_t> hanging;
  for (size_t p = 0; p < L.numPairs(); ++p)
    if (!L.pairIsOwn[p]) hanging.insert(L.elemVerts[p]);
  EXPECT_EQ(s.hangingVertices, hanging.size());
  EXPECT_GT(s.hangingVertices, 0u);
}

// ---------------------------------------------------------------------------------------------
// The point of the gradational layout (sec. 3.4)
// ---------------------------------------------------------------------------------------------

TEST(Layout, GradationalUsesFewerPairsAndElementsOnLargerSpheres) {
  for (auto [dim, n] : {std::pair{3, 16}, {3, 24}, {3, 32}, {2, 32}, {2, 64}}) {
    const VoxelVolume vol = sphere(n, dim);
    const Layout g = buildLayout(vol, LayoutKind::Gradational);
    const Layout u = buildLayout(vol, LayoutKind::Uniform);
    const Layout v = buildLayout(vol, LayoutKind::Voxel);
    EXPECT_LT(g.numPairs(), u.numPairs()) << "dim " << dim << " n " << n;
    EXPECT_LT(u.numPairs(), v.numPairs()) << "dim " << dim << " n " << n;
    EXPECT_LT(g.numElements(), u.numElements());
    EXPECT_LT(g.numVertices(), u.numVertices());
    EXPECT_GT(g.numLevels(), 1);
  }
}

TEST(Layout, LevelCountGrowsWithSize) {
  // Full cubes: 2 and 4 -> 1 level, 8 -> 2, 16 -> 3 (see the 8x8 and 12x12 squares above for
  // the pattern); beyond that, non-decreasing and more levels at 64 than at 16.
  std::vector<int> levels;
  for (int n : {2, 4, 8, 16, 32, 64})
    levels.push_back(buildLayout(filledBox(3, n, n, n), LayoutKind::Gradational).numLevels());
  EXPECT_EQ(levels[0], 1);
  EXPECT_EQ(levels[1], 1);
  EXPECT_EQ(levels[2], 2);
  EXPECT_EQ(levels[3], 3);
  EXPECT_TRUE(std::is_sorted(levels.begin(), levels.end()));
  EXPECT_GT(levels[5], levels[3]);
  for (int n : {16, 32, 64}) EXPECT_EQ(buildLayout(sphere(n, 3), LayoutKind::Uniform).numLevels(), 1);
}

// Counting a layout without building it (issue 15: `gradel layout --size 512` built the voxel
// baseline, 13 GB): countLayout gives the built layout's elements and vertices exactly and its
// pairs within the estimate's 3^dim per element; voxelLayoutStats equals layoutStats of the
// built voxel layout. Random volumes (holes, thin parts) and presets, 2D and 3D.
TEST(Layout, CountsWithoutBuildingMatchTheBuiltLayout) {
  std::vector<VoxelVolume> volumes = {sphere(12, 3), sphere(13, 2), filledBox(3, 9, 6, 5), filledBox(2, 7, 5, 1)};
  for (uint32_t seed = 1; seed <= 6; ++seed)
    volumes.push_back(randomVolume(seed % 2 ? 3 : 2, 11, 9, seed % 2 ? 7 : 1, 0.3 + 0.1 * seed, seed));
  for (const VoxelVolume& v : volumes) {
    if (v.countFilled() == 0) continue;
    for (LayoutKind kind : {LayoutKind::Gradational, LayoutKind::Uniform, LayoutKind::Voxel}) {
      SCOPED_TRACE(std::string(layoutKindName(kind)) + " " + std::to_string(v.nx()) + "x" + std::to_string(v.ny()) +
                   "x" + std::to_string(v.nz()));
      const Layout L = buildLayout(v, kind);
      const LayoutCounts c = countLayout(v, kind);
      EXPECT_EQ(c.elements, L.numElements());
      EXPECT_EQ(c.vertices, L.numVertices());
      EXPECT_GE(c.pairsEstimate, L.numPairs());
      if (kind == LayoutKind::Voxel) {
        EXPECT_EQ(c.pairsEstimate, L.numPairs());
        const LayoutStats built = layoutStats(L, v), counted = voxelLayoutStats(v);
        EXPECT_EQ(counted.voxels, built.voxels);
        EXPECT_EQ(counted.elements, built.elements);
        EXPECT_EQ(counted.elementsPerLevel, built.elementsPerLevel);
        EXPECT_EQ(counted.uniqueVertices, built.uniqueVertices);
        EXPECT_EQ(counted.pairs, built.pairs);
        EXPECT_EQ(counted.hangingVertices, built.hangingVertices);
        EXPECT_EQ(counted.hangingPairs, built.hangingPairs);
      }
    }
  }
}

}  // namespace
}  // namespace gradel

namespace gradel {
namespace {

// vertexAt through the row index (buildLayout makes it) answers exactly what the search of all
// vertices answers (a layout made by hand, without the index): every lattice point of random
// volumes and spheres, 2D and 3D, every layout, and points off the lattice.
TEST(Layout, VertexAtRowIndexMatchesTheFullSearch) {
  std::vector<VoxelVolume> volumes = {sphere(9, 3), sphere(12, 2), randomVolume(3, 7, 5, 6, 0.6, 3),
                                      randomVolume(2, 9, 6, 1, 0.5, 4)};
  for (const VoxelVolume& vol : volumes)
    for (LayoutKind kind : {LayoutKind::Gradational, LayoutKind::Uniform, LayoutKind::Voxel}) {
      const Layout indexed = buildLayout(vol, kind);
      ASSERT_EQ(indexed.rowStart.back(), indexed.numVertices());
      Layout plain = indexed;
      plain.rowStart.clear();
      size_t found = 0;
      for (int z = -1; z <= indexed.dims[2] + 1; ++z)
        for (int y = -1; y <= indexed.dims[1] + 1; ++y)
          for (int x = -1; x <= indexed.dims[0] + 1; ++x) {
            const uint32_t a = indexed.vertexAt(Int3(x, y, z)), b = plain.vertexAt(Int3(x, y, z));
            ASSERT_EQ(a, b) << x << " " << y << " " << z;
            if (a == Layout::kNoVertex) continue;
            ASSERT_EQ(indexed.vertices[a], Int3(x, y, z));
            ++found;
          }
      EXPECT_EQ(found, indexed.numVertices());  // every vertex found at its own point
    }
}

}  // namespace
}  // namespace gradel
