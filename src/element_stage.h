// The explicit step's hot loops: eq. 1 for every element, then each vertex's force gathered and
// integrated (eqs. 2-3), laid out for speed.
//
// The element is element.h's (c = mean x_i, A = sum (x_i - c) R0_i^T, M = best-fit rotation,
// f_i = k_e (M R0_i - x_i + e) with e = c - M sum R0 / n, the rounding residue's share removed),
// split in two passes that need no locks and no colouring:
//  1. per element (computeElementFrames): moments, the rotation fitted four elements at a time
//     (fitRotation3Batch), and the element's "frame": the columns of G = k_e M and
//     t = (k_e (e - M C_e), k_e), C_e the rest centroid;
//  2. per vertex (gatherVertexForces): with R0 = X_v - C_e (X_v the rest position),
//     f_v = sum_e k_e (M R0 + e - x_v) = (sum_e G_e) X_v + sum_e t_e - (sum_e k_e) x_v:
//     four 4-wide additions per pair, in a fixed order (the vertex's elements in id order).
// Each vertex is one 4-wide register (x, y, z, 0), so a pair of pass 1 costs a load, three
// broadcasts and four fused multiply-adds; pass 1 prefetches the vertices of the elements two
// batches ahead, since large bodies are bound by these indirect gathers. Every sum is formed in an order that does not
// depend on how ranges are split, so the result is the same at any thread count; it equals element.h's reference kernel
// to rounding (tested).
#pragma once

#include <vector>

#include "gradel/model.h"
#include "simd.h"

namespace gradel {

/// Per element, written by pass 1 and read by pass 2: the columns of k_e M (lane 3 zero) and
/// (k_e (e - M C_e), k_e). 128 bytes, aligned for 4-wide loads.
struct alignas(32) ElementFrame {
  Real c0[4], c1[4], c2[4], t[4];
};

/// Rest data of the two passes, derived once from the RestModel.
struct ElementStageRest {
  std::vector<Vec3> sumRestOffsets;      ///< Per element: sum_i R0_i (a rounding residue, ~1e-16).
  std::vector<Vec3> restCentroids;       ///< Per element: C_e [m], the mean rest position of its vertices.
  std::vector<uint32_t> vertexStart;     ///< Per vertex + 1: its range in vertexElements.
  std::vector<uint32_t> vertexElements;  ///< The elements of each vertex, ascending.

  explicit ElementStageRest(const RestModel& model);
  size_t memoryBytes() const;
};

/// Pass 1 over elements [begin, end): updates their rotations (warm start in, fit out) and writes
/// their frames. maxIterations bounds the 3D rotation refinement (as fitRotation3).
void computeElementFrames(const RestModel& model, const ElementStageRest& rest, size_t begin, size_t end,
                          const Vec3* positions, Quat* rotations, ElementFrame* frames, int maxIterations);

/// Pass 2 for vertices [begin, end): calls sink(v, f) with each vertex's elastic force f [N] as
/// (fx, fy, fz, 0). Inline, so that the caller's integration fuses with the gather.
template <class Sink>
inline void gatherVertexForces(const RestModel& model, const ElementStageRest& rest, const ElementFrame* frames,
                               const Vec3* positions, size_t begin, size_t end, Sink&& sink) {
  using namespace simd;
  const uint32_t* start = rest.vertexStart.data();
  const uint32_t* elements = rest.vertexElements.data();
  const Vec3* X = model.restPositions.data();
  for (size_t v = begin; v < end; ++v) {
    // sum G, sum t; lane 3 of sum t is sum k, which multiplies -x_v.
    d4 g0 = splat(0), g1 = g0, g2 = g0, t = g0;
    for (uint32_t j = start[v]; j < start[v + 1]; ++j) {
      const ElementFrame& f = frames[elements[j]];
      g0 += load4(f.c0), g1 += load4(f.c1), g2 += load4(f.c2), t += load4(f.t);
    }
    const Real* r = X[v].data();
    sink(v, g0 * r[0] + g1 * r[1] + g2 * r[2] + t - t[3] * loadVec3(positions[v]));
  }
}

}  // namespace gradel
