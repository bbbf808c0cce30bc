// The explicit step's hot loops: eq. 1 for every element, then each vertex's force gathered and
// integrated (eqs. 2-3), laid out for speed.
//
// The element is element.h's (c = mean x_i, A = sum (x_i - c) R0_i^T, M = best-fit rotation,
// f_i = k_e (M R0_i - x_i + e) with e = c - M sum R0 / n), split in two passes that need no locks
// and no colouring:
//  1. per element (computeElementFrames): moments, the rotation fitted four elements at a time
//     (fitRotation3Batch), and the element's "frame": the columns of G = k_e M,
//     t = k_e (e - M C_e) (C_e the rest centroid) and k_e, 104 bytes (ElementFrame);
//  2. per vertex (gatherVertexForces): with R0 = X_v - C_e (X_v the rest position),
//     f_v = sum_e k_e (M R0 + e - x_v) = (sum_e G_e) X_v + sum_e t_e - (sum_e k_e) x_v:
//     three 4-wide additions and one scalar per pair, in a fixed order (the vertex's elements in
//     id order).
// Rest offsets are lattice vectors: R0_i = h (P_i - mean P), P_i the vertex's lattice offset from
// the element's first vertex in voxels (h the voxel size of the element's body,
// RestModel::bodies), and since sum (x_i - c) = 0,
// A = h (sum x_i P_i^T - c sum P_i^T). Pass 1 streams the model's vertex id and a 4-byte record
// per pair ((P_i, 1) as four int8; int16 for blocks over 64 voxels) and forms the rows of
// sum x_i (P_i, 1)^T, whose last lane is sum x_i; the factor h does not change the fitted
// rotation, and sum P_i is an exact integer. Four
// elements' rows are then transposed into the rotation fit's lanes (the stage's constants are
// stored in those lanes already, ElementConstantGroup; the model's are loaded into them), and the
// frames computed four at a time and
// transposed back. Each vertex is one 4-wide register (x, y, z, 0); above kPrefetchAboveBytes of
// positions pass 1 prefetches the vertex of the pair kPrefetchPairs ahead, since large bodies are
// bound by these indirect gathers. Every sum is formed in an order that does not depend on how ranges are
// split, so the result is the same at any thread count; it equals element.h's reference kernel to
// rounding (tested).
// The volumetric term (Poisson's ratio > 0, element.h elementVolumeForces) is affine in the rest
// position too: f_v = H_e (X_v - C_e - mean R0) with H_e = -kappa_e e_v (D / tr S_e) M, so pass 1
// adds H_e to G and -H_e (C_e + mean R0) to t, and pass 2 is unchanged; e_v = (D h / tr S_e)
// tr(M^T A / h) - D from the moments and rotation pass 1 has anyway, four elements at a time
// (~40 flops per element). A model without a volumetric term (every poisson_ratio 0) has no
// ElementVolumeGroup and does none of this work.
#pragma once

#include <algorithm>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "gradel/model.h"
#include "simd.h"

namespace gradel {

/// Per element, written by pass 1 and read by pass 2: the columns of G = k_e M, each with one
/// component of t = k_e (e - M C_e) in lane 3 (c_j = (G_0j, G_1j, G_2j, t_j)), and k_e. 104 bytes,
/// packed (the vertex gather's loads need no alignment; a zero lane per column and padding to
/// 128 took 3.6 bytes per vertex on a gradational sphere).
struct ElementFrame {
  Real c0[4], c1[4], c2[4];
  Real k;
};
static_assert(sizeof(ElementFrame) == 104, "the frame is packed");

/// Per element, read by pass 1 four at a time: (sum_i P_i, 1 / n), (C_e [m], k_e [N/m]) and
/// (sum_i R0_i / n [m], 0), the mean rest offset as pass 2 forms it (R0_i = X_i - C_e in floating
/// point: a rounding residue, ~1e-16 |X|). Of these the stage stores only sum P and mean R0
/// (ElementConstantGroup); n, C_e and k_e are the model's (elemStart, restCentroids, stiffness),
/// loaded into lanes by the pass.
struct ElementConstants {
  Real sumLattice[3], invCount;
  Real restCentroid[3], stiffness;
  Real meanRestOffset[3];
};

/// The stage's own constants of four consecutive elements 4g .. 4g + 3, stored as pass 1 uses
/// them: one row of four lanes (one element each) per quantity, so a batch loads its lanes without
/// transposing. sum P is an integer (exact in a float). Lanes past the last element are zero.
struct alignas(16) ElementConstantGroup {
  Real meanRestOffset[3][4];
  float sumLattice[3][4];
};

/// The volumetric term's constants of four consecutive elements, in lanes as ElementConstantGroup:
/// D h / tr S_e [1/m] and kappa_e D / tr S_e [N/m]. A lane with kappa 0 contributes nothing; a
/// group of four zeros is skipped.
struct alignas(32) ElementVolumeGroup {
  Real strainScale[4];
  Real stiffness[4];
  /// A group with an element whose S_e is anisotropic (element.h volumeStrainMatrix) takes the
  /// general form: shape = h V_e per lane (an isotropic lane's h (D / tr S_e) I), F = (A / h) shape,
  /// its own rotation fit M_F, and kappaOverH = kappa_e / h [N/m]. Otherwise (anisotropic 0) the
  /// scalar form above, and these are unused.
  Real shape[9][4];
  Real kappaOverH[4];
  int32_t anisotropic = 0;
};

/// Pass 2 finds a vertex's elements from its count (vertexCount) and the start of its block of
/// kVertexStartStride vertices (vertexBlockStart).
constexpr size_t kVertexStartStride = 16;

/// The accuracy of the step's rotation fit [rad]: fitRotation3Batch's tolerance in pass 1 (warm
/// started from the element's last rotation, State::rotations). Eq. 1 is the element's torque
/// balance, so this tolerance is what keeps angular momentum: at 1e-8 rad (one Newton iteration
/// for elements that turned < 1e-4 rad, 1-4 instructions per vertex-step less) an isolated body
/// lost 7e-7 to 1.6e-6 of its angular momentum in 10^4 steps (test_dynamics.cpp allows 1e-9), so
/// the step keeps 1e-12 (docs/speed.md, "A leaner step (issue 31)").
constexpr Real kFrameRotationTolerance = 1e-12;

/// Pass 1 prefetches the vertex of the pair this many pairs ahead (~2 batches of 4 elements)...
constexpr size_t kPrefetchPairs = 128;
/// ... when the positions take more than this many bytes: smaller ones stay in the caches, where
/// the out-of-order core overlaps the gathers by itself and a prefetch is three instructions a
/// pair for nothing (paper setting, sphere n = 32, 7,037 vertices).
constexpr size_t kPrefetchAboveBytes = size_t(2) << 20;

/// Rest data of the two passes, derived once from the RestModel.
struct ElementStageRest {
  std::vector<ElementConstantGroup> groups;  ///< Element e's constants: lane e % 4 of groups[e / 4].
  /// As groups, for the volumetric term; empty when the model has none (RestModel::hasVolumeTerm).
  std::vector<ElementVolumeGroup> volume;
  /// Per pair, in the model's pair order (its vertex: RestModel::elemVerts), (P_i, 1): P_i the
  /// vertex's lattice offset [voxels] from the element's first vertex. Four bytes a pair when
  /// every offset of the model is in [-128, 127] (blocks up to 64 voxels across: -32 to 64 on the
  /// gradational sphere n = 256), else four int16 in lattice16; the other vector is empty.
  /// std::logic_error when a rest position is off the model's voxel lattice, or when the model
  /// is too large for 32-bit byte offsets (over ~178 M vertices or ~33 M elements).
  std::vector<int8_t> lattice8;
  std::vector<int16_t> lattice16;
  /// Per vertex: how many elements it has (at most 255: a vertex of a layout is in at most 8
  /// blocks; std::logic_error otherwise), their frames' offsets in vertexFrames.
  std::vector<uint8_t> vertexCount;
  /// No vertex count is 0 (a built model's vertices are its elements' corners): the gather then
  /// does not test for a vertex without frames.
  bool everyVertexInAnElement = true;
  /// Per kVertexStartStride vertices + 1: where the first vertex of the block starts in vertexFrames.
  std::vector<uint32_t> vertexBlockStart;
  std::vector<uint32_t> vertexFrames;  ///< The elements of each vertex, ascending, as frame byte offsets (e * 104).

  explicit ElementStageRest(const RestModel& model);
  /// Element e's constants, gathered from its lane and the model (tests).
  ElementConstants constants(const RestModel& model, size_t e) const;
  void lattice(size_t pair, int out[4]) const;  ///< Pair p's (P, 1) (tests).
  /// Where vertex v's frames start in vertexFrames (the prefix of vertexCount).
  uint32_t vertexStart(size_t v) const {
    uint32_t j = vertexBlockStart[v / kVertexStartStride];
    for (size_t u = v / kVertexStartStride * kVertexStartStride; u < v; ++u) j += vertexCount[u];
    return j;
  }
  size_t memoryBytes() const;
};

/// Pass 1 over elements [begin, end): updates their rotations (warm start in, fit out) and writes
/// their frames. maxIterations bounds the 3D rotation refinement (as fitRotation3). begin must be
/// a multiple of kRotationLanes (the constants' groups; std::logic_error otherwise).
void computeElementFrames(const RestModel& model, const ElementStageRest& rest, size_t begin, size_t end,
                          const Vec3* positions, Quat* rotations, ElementFrame* frames, int maxIterations);

/// Pass 2 for vertices [begin, end): calls sink(v, p, k) with p = G X_v + t (lane 3 not a
/// component) and k = sum k_e, each vertex's elastic force [N] being p - k x_v (the sink loads x_v
/// anyway). Inline, so that the caller's integration fuses with the gather.
template <class Sink>
inline void gatherVertexForces(const RestModel& model, const ElementStageRest& rest, const ElementFrame* frames,
                               size_t begin, size_t end, Sink&& sink) {
  using namespace simd;
  const uint8_t* count = rest.vertexCount.data();
  const char* base = reinterpret_cast<const char*>(frames);
  const Vec3* X = model.restPositions.data();
  const uint32_t* j = rest.vertexFrames.data() + rest.vertexStart(begin);
  auto vertex = [&](size_t v, auto everyVertexInAnElement) {
    // sum G with sum t in lane 3 of its columns, and sum k, which multiplies -x_v. The first
    // frame starts the sums (a vertex of no element gets zero force).
    const uint32_t* je = j + count[v];
    d4 g0 = splat(0), g1 = g0, g2 = g0;
    Real k = 0;
    if (everyVertexInAnElement() || j != je) {
      const ElementFrame& f = *reinterpret_cast<const ElementFrame*>(base + *j++);
      g0 = load4(f.c0), g1 = load4(f.c1), g2 = load4(f.c2), k = f.k;
    }
    for (; j != je; ++j) {
      const ElementFrame& f = *reinterpret_cast<const ElementFrame*>(base + *j);
      g0 += load4(f.c0), g1 += load4(f.c1), g2 += load4(f.c2), k += f.k;
    }
    j = je;  // (it is: said here, the compiler takes je instead of recomputing j from the loop counter)
    const Real* r = X[v].data();
    // (g0 r0 + g1 r1 + g2 r2 + t) - k x, summed as sink does: sink gets the first part and k.
    sink(v, g0 * r[0] + g1 * r[1] + g2 * r[2] + laneThrees(g0, g1, g2), k);
  };
  auto loops = [&](auto everyVertexInAnElement) {
    for (size_t v = begin; v < end; ++v) vertex(v, everyVertexInAnElement);
  };
  rest.everyVertexInAnElement ? loops(std::true_type{}) : loops(std::false_type{});
}

}  // namespace gradel
