#include "element_stage.h"

#include <algorithm>
#include <cmath>

#include "gradel/rotation_fit.h"
#include "simd.h"

namespace gradel {

namespace {

using namespace simd;

// Sums over one element's pairs: s = sum x_i and the columns a_c = sum x_i R0_i[c] (A before
// centring). R0 streams in pair order (the hardware prefetches it); the gathers of x are
// prefetched by the caller. Two interleaved accumulator sets hide the fused multiply-adds'
// latency.
struct ElementMoments {
  d4 s, a0, a1, a2;
};

inline ElementMoments elementMoments(const Vec3* x, const Vec3* R0, const uint32_t* verts, uint32_t n) {
  d4 s0 = splat(0), s1 = splat(0), a0 = s0, a1 = s0, a2 = s0, b0 = s0, b1 = s0, b2 = s0;
  uint32_t i = 0;
  for (; i + 1 < n; i += 2) {
    const d4 p = loadVec3(x[verts[i]]), q = loadVec3(x[verts[i + 1]]);
    const Real* r = R0[i].data();
    const Real* t = R0[i + 1].data();
    s0 += p, a0 += p * r[0], a1 += p * r[1], a2 += p * r[2];
    s1 += q, b0 += q * t[0], b1 += q * t[1], b2 += q * t[2];
  }
  if (i < n) {
    const d4 p = loadVec3(x[verts[i]]);
    const Real* r = R0[i].data();
    s0 += p, a0 += p * r[0], a1 += p * r[1], a2 += p * r[2];
  }
  return {s0 + s1, a0 + b0, a1 + b1, a2 + b2};
}

}  // namespace

ElementStageRest::ElementStageRest(const RestModel& m)
    : sumRestOffsets(m.numElements(), Vec3::Zero()), restCentroids(m.numElements(), Vec3::Zero()) {
  const size_t V = m.numVertices(), E = m.numElements();
  for (size_t e = 0; e < E; ++e) {
    // The same summation order as element.cpp's reference kernel.
    Real s0 = 0, s1 = 0, s2 = 0;
    Vec3 c = Vec3::Zero();
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) {
      s0 += m.restOffsets[p].x(), s1 += m.restOffsets[p].y(), s2 += m.restOffsets[p].z();
      c += m.restPositions[m.elemVerts[p]];
    }
    sumRestOffsets[e] = Vec3(s0, s1, s2);
    restCentroids[e] = c / Real(m.elemStart[e + 1] - m.elemStart[e]);
  }
  // Transpose element -> vertex into vertex -> elements, ascending per vertex.
  vertexStart.assign(V + 1, 0);
  for (uint32_t v : m.elemVerts) ++vertexStart[v + 1];
  for (size_t v = 0; v < V; ++v) vertexStart[v + 1] += vertexStart[v];
  vertexElements.resize(m.numPairs());
  std::vector<uint32_t> fill(vertexStart.begin(), vertexStart.end() - 1);
  for (uint32_t e = 0; e < E; ++e)
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) vertexElements[fill[m.elemVerts[p]]++] = e;
}

size_t ElementStageRest::memoryBytes() const {
  return (sumRestOffsets.capacity() + restCentroids.capacity()) * sizeof(Vec3) +
         (vertexStart.capacity() + vertexElements.capacity()) * sizeof(uint32_t);
}

void computeElementFrames(const RestModel& m, const ElementStageRest& rest, size_t begin, size_t end, const Vec3* x,
                          Quat* rotations, ElementFrame* frames, int maxIterations) {
  constexpr int L = kRotationLanes;
  constexpr size_t kPrefetchBatches = 2;  // 4 and 8 measured no better at n = 288
  RotationBatch batch;
  d4 centroid[L];
  for (size_t e0 = begin; e0 < end; e0 += L) {
    const int lanes = int(std::min<size_t>(L, end - e0));
    // The vertices of the batch after next, fetched ahead: the pair list says where they are,
    // which no hardware prefetcher can guess (large bodies are bound by these gathers).
    if (e0 + (kPrefetchBatches + 1) * L <= end)
      for (uint32_t p = m.elemStart[e0 + kPrefetchBatches * L]; p < m.elemStart[e0 + (kPrefetchBatches + 1) * L]; ++p) {
        __builtin_prefetch(&x[m.elemVerts[p]]);
      }
    // 1. Moments: centroid and A = sum (x_i - c) R0_i^T = sum x_i R0_i^T - c (sum R0_i)^T.
    for (int l = 0; l < L; ++l) {
      if (l >= lanes) {  // padding: A = I, q = I converges at once
        for (int k = 0; k < 9; ++k) batch.A[k][l] = k % 4 == 0 ? 1 : 0;
        batch.q[0][l] = 1, batch.q[1][l] = batch.q[2][l] = batch.q[3][l] = 0;
        continue;
      }
      const size_t e = e0 + l;
      const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
      const ElementMoments mo = elementMoments(x, &m.restOffsets[b], &m.elemVerts[b], n);
      const d4 c = mo.s / Real(n);
      const Vec3& sr = rest.sumRestOffsets[e];
      const d4 col[3] = {mo.a0 - c * sr.x(), mo.a1 - c * sr.y(), mo.a2 - c * sr.z()};
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) batch.A[3 * r + k][l] = col[k][r];
      centroid[l] = c;
      const Quat& q = rotations[e];
      batch.q[0][l] = q.w(), batch.q[1][l] = q.x(), batch.q[2][l] = q.y(), batch.q[3][l] = q.z();
    }
    // 2. Best-fit rotations (eq. 1), four at once; 2D has a closed form (rotation about z).
    if (m.dim == 2) {
      for (int l = 0; l < lanes; ++l) {
        Mat3 A;
        for (int k = 0; k < 9; ++k) A(k / 3, k % 3) = batch.A[k][l];
        const Real th = fitRotation2(A), cs = std::cos(th), sn = std::sin(th);
        batch.q[0][l] = std::cos(0.5 * th), batch.q[1][l] = 0, batch.q[2][l] = 0, batch.q[3][l] = std::sin(0.5 * th);
        const Real M[9] = {cs, -sn, 0, sn, cs, 0, 0, 0, 1};
        for (int k = 0; k < 9; ++k) batch.M[k][l] = M[k];
      }
    } else {
      fitRotation3Batch(batch, maxIterations, 1e-12);
    }
    // 3. Frames: G = k M and t = (k (e - M C), k), e = c - M sum R0 / n.
    for (int l = 0; l < lanes; ++l) {
      const size_t e = e0 + l;
      const uint32_t n = m.elemStart[e + 1] - m.elemStart[e];
      rotations[e] = Quat(batch.q[0][l], batch.q[1][l], batch.q[2][l], batch.q[3][l]);
      const Real k = m.stiffness[e];
      const d4 col0 = {batch.M[0][l], batch.M[3][l], batch.M[6][l], 0};
      const d4 col1 = {batch.M[1][l], batch.M[4][l], batch.M[7][l], 0};
      const d4 col2 = {batch.M[2][l], batch.M[5][l], batch.M[8][l], 0};
      const Vec3& sr = rest.sumRestOffsets[e];
      const Vec3& C = rest.restCentroids[e];
      d4 t = k * (centroid[l] - (col0 * sr.x() + col1 * sr.y() + col2 * sr.z()) / Real(n) -
                  (col0 * C.x() + col1 * C.y() + col2 * C.z()));
      t[3] = k;
      ElementFrame& f = frames[e];
      store4(f.c0, k * col0), store4(f.c1, k * col1), store4(f.c2, k * col2), store4(f.t, t);
    }
  }
}

}  // namespace gradel
