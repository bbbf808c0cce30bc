#include "element_stage.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "gradel/element.h"
#include "gradel/material.h"
#include "gradel/rotation_fit.h"
#include "simd.h"

namespace gradel {

namespace {

using namespace simd;

// One element's rows of sum x_i (P_i, 1)^T: row j is (sum x_i[j] P_i, sum x_i[j]). The pairs
// (the model's vertex ids and the stage's lattice records) stream in order (the hardware
// prefetches them); the gathers of x are not predictable, so with Prefetch each pair prefetches
// the vertex of the pair kPrefetchPairs ahead (the caller makes sure that pair exists). Two
// interleaved accumulator sets hide the fused multiply-adds' latency.
struct ElementRows {
  d4 r0, r1, r2;
};

inline d4 loadLattice(const int8_t* p) { return loadInt8x4(p); }
inline d4 loadLattice(const int16_t* p) { return loadInt16x4(p); }

template <bool Prefetch, class Lattice>
inline ElementRows elementRows(const char* x, const uint32_t* vertex, const Lattice* lattice, size_t n) {
  constexpr size_t S = sizeof(Vec3);
  d4 a0 = splat(0), a1 = a0, a2 = a0, b0 = a0, b1 = a0, b2 = a0;
  size_t i = 0;
  if (n >= 2) {  // the first two pairs start the sums (instead of six zeroed registers)
    if constexpr (Prefetch) {
      __builtin_prefetch(x + vertex[kPrefetchPairs] * S);
      __builtin_prefetch(x + vertex[1 + kPrefetchPairs] * S);
    }
    const Real* p = reinterpret_cast<const Real*>(x + vertex[0] * S);
    const Real* q = reinterpret_cast<const Real*>(x + vertex[1] * S);
    const d4 u = loadLattice(lattice), w = loadLattice(lattice + 4);
    a0 = p[0] * u, a1 = p[1] * u, a2 = p[2] * u;
    b0 = q[0] * w, b1 = q[1] * w, b2 = q[2] * w;
    i = 2;
  }
#pragma GCC unroll 2
  for (; i + 1 < n; i += 2) {
    if constexpr (Prefetch) {
      __builtin_prefetch(x + vertex[i + kPrefetchPairs] * S);
      __builtin_prefetch(x + vertex[i + 1 + kPrefetchPairs] * S);
    }
    const Real* p = reinterpret_cast<const Real*>(x + vertex[i] * S);
    const Real* q = reinterpret_cast<const Real*>(x + vertex[i + 1] * S);
    const d4 u = loadLattice(lattice + 4 * i), w = loadLattice(lattice + 4 * i + 4);
    a0 += p[0] * u, a1 += p[1] * u, a2 += p[2] * u;
    b0 += q[0] * w, b1 += q[1] * w, b2 += q[2] * w;
  }
  if (i < n) {
    if constexpr (Prefetch) __builtin_prefetch(x + vertex[i + kPrefetchPairs] * S);
    const Real* p = reinterpret_cast<const Real*>(x + vertex[i] * S);
    const d4 u = loadLattice(lattice + 4 * i);
    a0 += p[0] * u, a1 += p[1] * u, a2 += p[2] * u;
  }
  return {a0 + b0, a1 + b1, a2 + b2};
}

}  // namespace

ElementStageRest::ElementStageRest(const RestModel& m) : groups((m.numElements() + 3) / 4, ElementConstantGroup{}) {
  const size_t V = m.numVertices(), E = m.numElements(), P = m.numPairs();
  // Pass 1 reads positions at vertex * 24 and the vertex gather frames at element * 104, 32-bit.
  if (V > UINT32_MAX / sizeof(Vec3) || E > UINT32_MAX / sizeof(ElementFrame))
    throw std::logic_error("ElementStageRest: the model is too large for 32-bit offsets");
  // Each element's lattice is its body's (bodies.h): h per body; a model without bodies (made
  // by hand) is one body of m.voxelSize. Only this set-up reads h; the passes do not.
  std::vector<int16_t> lattice(4 * P);
  bool narrow = true;  // every offset in [-128, 127]: one byte each
  size_t body = 0;
  std::vector<Vec3> R0;
  for (size_t e = 0; e < E; ++e) {
    while (body < m.bodies.size() && e >= m.bodies[body].elementEnd) ++body;
    const Real h = body < m.bodies.size() ? m.bodies[body].voxelSize : m.voxelSize;
    const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    Vec3 residue = Vec3::Zero();
    Eigen::Vector3i sum = Eigen::Vector3i::Zero();
    const Vec3& first = m.restPositions[m.elemVerts[b]];
    for (uint32_t p = b; p < b + n; ++p) {
      const Vec3& X = m.restPositions[m.elemVerts[p]];
      for (int a = 0; a < 3; ++a) {
        const Real d = (X[a] - first[a]) / h, r = std::round(d);
        // Rest positions are origin + lattice * h (model.h): d is an integer to rounding.
        if (!(std::abs(d - r) <= 1e-3) || std::abs(r) > 32767)
          throw std::logic_error("ElementStageRest: a rest position is off the voxel lattice");
        lattice[4 * size_t(p) + a] = int16_t(r);
        narrow = narrow && r >= -128 && r <= 127;
        sum[a] += int(r);
      }
      lattice[4 * size_t(p) + 3] = 1;
    }
    // The mean of the model's rest offsets X - C (RestModel::restOffset), as pass 2 forms them.
    for (uint32_t p = b; p < b + n; ++p) residue += m.restOffset(e, p);
    residue /= Real(n);
    ElementConstantGroup& k = groups[e / 4];
    const size_t l = e % 4;
    for (int a = 0; a < 3; ++a) k.sumLattice[a][l] = float(sum[a]), k.meanRestOffset[a][l] = residue[a];
    if (std::abs(sum[0]) > (1 << 24) || std::abs(sum[1]) > (1 << 24) || std::abs(sum[2]) > (1 << 24))
      throw std::logic_error("ElementStageRest: an element too large for its lattice sum in a float");
    if (m.hasVolumeTerm()) {
      if (volume.empty()) {  // a padding lane keeps shape I: its F = A = I fits the identity
        ElementVolumeGroup none{};
        for (int k : {0, 4, 8})
          for (int lane = 0; lane < 4; ++lane) none.shape[k][lane] = 1;
        volume.assign(groups.size(), none);
      }
      ElementVolumeGroup& vg = volume[e / 4];
      m.restOffsets(e, R0);
      const Real g = Real(m.dim == 2 ? 2 : 3) / restMomentTrace(R0.data(), int(n));
      vg.strainScale[l] = g * h;
      vg.stiffness[l] = m.volumeStiffness[e] * g;
      Mat3 V;
      if (volumeStrainMatrix(m.dim, R0.data(), int(n), V)) vg.anisotropic = 1;
      else V = g * Mat3::Identity();
      for (int k = 0; k < 9; ++k) vg.shape[k][l] = h * V(k / 3, k % 3);
      vg.kappaOverH[l] = m.volumeStiffness[e] / h;
    }
  }
  if (narrow)
    lattice8.assign(lattice.begin(), lattice.end());
  else
    lattice16 = std::move(lattice);
  // Transpose element -> vertex into vertex -> elements, ascending per vertex.
  std::vector<uint32_t> start(V + 1, 0);
  for (uint32_t v : m.elemVerts) ++start[v + 1];
  vertexCount.resize(V);
  for (size_t v = 0; v < V; ++v) {
    if (start[v + 1] > 255) throw std::logic_error("ElementStageRest: a vertex in more than 255 elements");
    vertexCount[v] = uint8_t(start[v + 1]);
    everyVertexInAnElement = everyVertexInAnElement && start[v + 1] > 0;
    start[v + 1] += start[v];
  }
  vertexBlockStart.resize((V + kVertexStartStride - 1) / kVertexStartStride + 1);
  for (size_t k = 0; k < vertexBlockStart.size(); ++k) vertexBlockStart[k] = start[std::min(V, k * kVertexStartStride)];
  vertexFrames.resize(P);
  for (uint32_t e = 0; e < E; ++e)
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p)
      vertexFrames[start[m.elemVerts[p]]++] = uint32_t(e * sizeof(ElementFrame));
}

ElementConstants ElementStageRest::constants(const RestModel& m, size_t e) const {
  const ElementConstantGroup& k = groups.at(e / 4);
  const size_t l = e % 4;
  ElementConstants c;
  for (int a = 0; a < 3; ++a)
    c.sumLattice[a] = k.sumLattice[a][l], c.restCentroid[a] = m.restCentroids[e][a], c.meanRestOffset[a] = k.meanRestOffset[a][l];
  c.invCount = 1.0 / Real(m.elemStart[e + 1] - m.elemStart[e]), c.stiffness = m.stiffness[e];
  return c;
}

void ElementStageRest::lattice(size_t p, int out[4]) const {
  for (int a = 0; a < 4; ++a) out[a] = lattice8.empty() ? lattice16.at(4 * p + a) : lattice8.at(4 * p + a);
}

size_t ElementStageRest::memoryBytes() const {
  return groups.capacity() * sizeof(ElementConstantGroup) + volume.capacity() * sizeof(ElementVolumeGroup) +
         lattice8.capacity() + lattice16.capacity() * sizeof(int16_t) + vertexCount.capacity() +
         (vertexBlockStart.capacity() + vertexFrames.capacity()) * sizeof(uint32_t);
}

namespace {

// The volumetric term of four elements into their frames (element_stage.h):
// e_v = (D h / tr S) tr(M^T A / h) - D, H = -(kappa D / tr S) e_v M; G += H, t -= H (C + mean R0).
// K as in elementFrames; Fr[col][row] the frames before the transpose.
// H = -kappa e_v M_F V per lane (element.h's general form): F = (A / h) shape, M_F its own fit
// (3D: four lanes at once, warm-started from A's rotations; 2D: the closed form),
// e_v = tr(M_F^T F) - D, H = -(kappa / h) e_v M_F shape.
inline void anisotropicVolumeTerm(const ElementVolumeGroup& vg, int dim, const RotationBatch& batch, int maxIterations,
                                  d4* H) {
  RotationBatch fit;
  d4 P[9];
  for (int k = 0; k < 9; ++k) P[k] = load4(vg.shape[k]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      store4(fit.A[3 * r + c], load4(batch.A[3 * r]) * P[c] + load4(batch.A[3 * r + 1]) * P[3 + c] +
                                   load4(batch.A[3 * r + 2]) * P[6 + c]);
  if (dim == 2) {
    for (int l = 0; l < kRotationLanes; ++l) {
      Mat3 F;
      for (int k = 0; k < 9; ++k) F(k / 3, k % 3) = fit.A[k][l];
      const Mat3 M = fitAffineRotation(2, F, Quat::Identity());
      for (int k = 0; k < 9; ++k) fit.M[k][l] = M(k / 3, k % 3);
    }
  } else {
    for (int k = 0; k < 4; ++k) store4(fit.q[k], load4(batch.q[k]));
    fitRotation3Batch(fit, maxIterations, kFrameRotationTolerance);
  }
  d4 MF[9];
  for (int k = 0; k < 9; ++k) MF[k] = load4(fit.M[k]);
  d4 tr = MF[0] * load4(fit.A[0]);
  for (int j = 1; j < 9; ++j) tr += MF[j] * load4(fit.A[j]);
  const d4 s = load4(vg.kappaOverH) * (splat(dim == 2 ? 2 : 3) - tr);  // -(kappa / h) e_v
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) H[3 * r + c] = s * (MF[3 * r] * P[c] + MF[3 * r + 1] * P[3 + c] + MF[3 * r + 2] * P[6 + c]);
}

inline void addVolumeTerm(const ElementVolumeGroup& vg, int dim, const RotationBatch& batch, int maxIterations,
                          const d4* M, const d4* K, d4 (*Fr)[4]) {
  const d4 kappa = load4(vg.stiffness);
  if (kappa[0] == 0 && kappa[1] == 0 && kappa[2] == 0 && kappa[3] == 0) return;
  d4 H[9];
  if (vg.anisotropic) {
    anisotropicVolumeTerm(vg, dim, batch, maxIterations, H);
  } else {
    d4 tr = M[0] * load4(batch.A[0]);
    for (int j = 1; j < 9; ++j) tr += M[j] * load4(batch.A[j]);
    const d4 s = kappa * (splat(dim == 2 ? 2 : 3) - load4(vg.strainScale) * tr);  // -kappa D / tr S e_v
    for (int j = 0; j < 9; ++j) H[j] = s * M[j];
  }
  for (int r = 0; r < 3; ++r) {
    const d4 h0 = H[3 * r], h1 = H[3 * r + 1], h2 = H[3 * r + 2];
    Fr[0][r] += h0, Fr[1][r] += h1, Fr[2][r] += h2;
    Fr[3][r] -= h0 * (K[4] + K[8]) + h1 * (K[5] + K[9]) + h2 * (K[6] + K[10]);
  }
}

template <bool Prefetch, class Lattice>
void elementFrames(const RestModel& m, const ElementStageRest& rest, const Lattice* lattice, size_t begin, size_t end,
                   const Vec3* x, Quat* rotations, ElementFrame* frames, int maxIterations) {
  static_assert(kRotationLanes == 4, "the transposes below are 4 x 4");
  constexpr int L = kRotationLanes;
  if (begin % L != 0) throw std::logic_error("computeElementFrames: begin is not a multiple of kRotationLanes");
  RotationBatch batch;
  const uint32_t* elemStart = m.elemStart.data();
  const uint32_t* vertex = m.elemVerts.data();
  const size_t E = m.numElements(), P = m.numPairs();
  const char* xb = reinterpret_cast<const char*>(x);
  for (size_t e0 = begin; e0 < end; e0 += L) {
    const int lanes = int(std::min<size_t>(L, end - e0));
    // 1. Rows of sum x_i (P_i, 1)^T per element, then transposed into lanes (one element per
    //    lane): S[j][k] = sum x_i[j] P_i[k], S[j][3] = sum x_i[j]. A padding lane gets rows
    //    (I, 0), sum P = 0 and q = I: A = I, which the fit leaves alone. The prefetch reads
    //    kPrefetchPairs pairs ahead: not in the model's last batches.
    const bool prefetch = Prefetch && elemStart[e0 + size_t(lanes)] + kPrefetchPairs <= P;
    d4 S[3][4], Q[4];
#pragma GCC unroll 4
    for (int l = 0; l < L; ++l) {
      if (l >= lanes) {
        S[0][l] = d4{1, 0, 0, 0}, S[1][l] = d4{0, 1, 0, 0}, S[2][l] = d4{0, 0, 1, 0};
        Q[l] = d4{0, 0, 0, 1};
        continue;
      }
      const size_t e = e0 + l;
      const uint32_t b = elemStart[e], n = elemStart[e + 1] - b;
      const ElementRows r = prefetch ? elementRows<true>(xb, vertex + b, lattice + 4 * size_t(b), n)
                                     : elementRows<false>(xb, vertex + b, lattice + 4 * size_t(b), n);
      S[0][l] = r.r0, S[1][l] = r.r1, S[2][l] = r.r2;
      Q[l] = load4(rotations[e].coeffs().data());  // x, y, z, w
    }
    for (int j = 0; j < 3; ++j) transpose(S[j][0], S[j][1], S[j][2], S[j][3]);
    transpose(Q[0], Q[1], Q[2], Q[3]);  // x, y, z, w
    // The stage's constants are stored in lanes already (a padding lane's are zero); 1 / n, C and
    // k are the model's, loaded into lanes (zero past the model's last element). Those used after
    // the fit are loaded after it (a call: no vector register survives it).
    const ElementConstantGroup& g = rest.groups[e0 / L];
    const bool full = e0 + L <= E;
    d4 K[11];  // sum P (3), 1 / n, C (3), k, mean R0 (3)
    for (int j = 0; j < 3; ++j) K[j] = loadFloat4(g.sumLattice[j]);
    if (full) {
      K[3] = 1.0 / loadCountDifference(elemStart + e0);
    } else {
      K[3] = splat(0);
      for (size_t e = e0; e < E; ++e) K[3][e - e0] = 1.0 / Real(elemStart[e + 1] - elemStart[e]);
    }
    // 2. Centroid c = sum x / n and A / h = sum x P^T - c (sum P)^T.
    d4 c[3];
    for (int j = 0; j < 3; ++j) {
      c[j] = S[j][3] * K[3];
      for (int k = 0; k < 3; ++k) store4(batch.A[3 * j + k], S[j][k] - c[j] * K[k]);
    }
    store4(batch.q[0], Q[3]), store4(batch.q[1], Q[0]), store4(batch.q[2], Q[1]), store4(batch.q[3], Q[2]);
    // 3. Best-fit rotations (eq. 1), four at once; 2D has a closed form (rotation about z).
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
      fitRotation3Batch(batch, maxIterations, kFrameRotationTolerance);
    }
    for (int j = 0; j < 3; ++j) K[8 + j] = load4(g.meanRestOffset[j]);
    if (full) {
      K[7] = load4(m.stiffness.data() + e0);
      const Vec3* C = m.restCentroids.data() + e0;
      d4 c0 = loadVec3(C[0]), c1 = loadVec3(C[1]), c2 = loadVec3(C[2]), c3 = loadVec3(C[3]);
      transpose(c0, c1, c2, c3);
      K[4] = c0, K[5] = c1, K[6] = c2;
    } else {
      for (int j = 4; j < 8; ++j) K[j] = splat(0);
      for (size_t e = e0; e < E; ++e) {
        K[7][e - e0] = m.stiffness[e];
        for (int a = 0; a < 3; ++a) K[4 + a][e - e0] = m.restCentroids[e][a];
      }
    }
    // 4. Frames, four at once: G = k M and t = k (e - M C), e = c - M mean R0 (the
    //    residue's share removed as in element.h: the forces then sum to zero to rounding),
    //    transposed back to one frame per element; the rotations likewise.
    d4 M[9];
    for (int k = 0; k < 9; ++k) M[k] = load4(batch.M[k]);
    const d4 k = K[7];
    d4 F[4][4];  // F[column][lane before the transpose] (F[3][3] unused: k is stored apart)
    for (int col = 0; col < 3; ++col) F[col][0] = k * M[col], F[col][1] = k * M[3 + col], F[col][2] = k * M[6 + col];
    for (int r = 0; r < 3; ++r)
      F[3][r] = k * (c[r] - (M[3 * r] * K[8] + M[3 * r + 1] * K[9] + M[3 * r + 2] * K[10]) -
                     (M[3 * r] * K[4] + M[3 * r + 1] * K[5] + M[3 * r + 2] * K[6]));
    if (!rest.volume.empty()) addVolumeTerm(rest.volume[e0 / L], m.dim, batch, maxIterations, M, K, F);
    for (int col = 0; col < 3; ++col) {  // t's components into lane 3 of G's columns (ElementFrame)
      F[col][3] = F[3][col];
      transpose(F[col][0], F[col][1], F[col][2], F[col][3]);
    }
    d4 q[4] = {load4(batch.q[1]), load4(batch.q[2]), load4(batch.q[3]), load4(batch.q[0])};
    transpose(q[0], q[1], q[2], q[3]);
    auto store = [&](int l) {
      ElementFrame& f = frames[e0 + l];
      store4(f.c0, F[0][l]), store4(f.c1, F[1][l]), store4(f.c2, F[2][l]), f.k = k[l];
      store4(rotations[e0 + l].coeffs().data(), q[l]);
    };
    if (lanes == L) {  // (lanes known: the frames stay in registers)
      store(0), store(1), store(2), store(3);
    } else {
      for (int l = 0; l < lanes; ++l) store(l);
    }
  }
}

}  // namespace

void computeElementFrames(const RestModel& m, const ElementStageRest& rest, size_t begin, size_t end, const Vec3* x,
                          Quat* rotations, ElementFrame* frames, int maxIterations) {
  auto run = [&](const auto* lattice) {
    if (m.numVertices() * sizeof(Vec3) > kPrefetchAboveBytes)
      elementFrames<true>(m, rest, lattice, begin, end, x, rotations, frames, maxIterations);
    else
      elementFrames<false>(m, rest, lattice, begin, end, x, rotations, frames, maxIterations);
  };
  rest.lattice8.empty() ? run(rest.lattice16.data()) : run(rest.lattice8.data());
}

}  // namespace gradel
