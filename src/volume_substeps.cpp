#include "volume_substeps.h"

#include <algorithm>
#include <stdexcept>

#include "simd.h"

namespace gradel {

namespace {

using namespace simd;

// Rows of sum x_i (P_i, 1)^T of one element, as pass 1 forms them (element_stage.cpp): two
// accumulator sets, added in the same order at any thread count.
inline void gatherRows(const char* x, const StagePair* pair, uint32_t n, d4& r0, d4& r1, d4& r2) {
  d4 a0 = splat(0), a1 = a0, a2 = a0, b0 = a0, b1 = a0, b2 = a0;
  uint32_t i = 0;
  for (; i + 1 < n; i += 2) {
    const Real* p = reinterpret_cast<const Real*>(x + pair[i].offset);
    const Real* q = reinterpret_cast<const Real*>(x + pair[i + 1].offset);
    const d4 u = loadInt16x4(pair[i].lattice), w = loadInt16x4(pair[i + 1].lattice);
    a0 += p[0] * u, a1 += p[1] * u, a2 += p[2] * u;
    b0 += q[0] * w, b1 += q[1] * w, b2 += q[2] * w;
  }
  if (i < n) {
    const Real* p = reinterpret_cast<const Real*>(x + pair[i].offset);
    const d4 u = loadInt16x4(pair[i].lattice);
    a0 += p[0] * u, a1 += p[1] * u, a2 += p[2] * u;
  }
  r0 = a0 + b0, r1 = a1 + b1, r2 = a2 + b2;
}

}  // namespace

void computeVolumeFrames(const RestModel& m, const ElementStageRest& rest, const VolumeBasisGroup* basis,
                         size_t begin, size_t end, const Vec3* x, ElementFrame* frames) {
  constexpr int L = 4;
  if (begin % L != 0) throw std::logic_error("computeVolumeFrames: begin is not a multiple of 4");
  const d4 D = splat(m.dim == 2 ? 2 : 3), zero = splat(0);
  for (size_t e0 = begin; e0 < end; e0 += L) {
    const int lanes = int(std::min<size_t>(L, end - e0));
    const ElementVolumeGroup& vg = rest.volume[e0 / L];
    const d4 kappa = load4(vg.kappaOverH);
    if (kappa[0] == 0 && kappa[1] == 0 && kappa[2] == 0 && kappa[3] == 0) {
      for (int l = 0; l < lanes; ++l) {
        ElementFrame& f = frames[e0 + l];
        store4(f.c0, zero), store4(f.c1, zero), store4(f.c2, zero), store4(f.t, zero);
      }
      continue;
    }
    d4 S[3][4];
    for (int l = 0; l < L; ++l) {
      if (l >= lanes) {  // a padding lane: kappa 0, any finite rows
        S[0][l] = S[1][l] = S[2][l] = zero;
        continue;
      }
      const size_t e = e0 + l;
      const uint32_t b = m.elemStart[e];
      gatherRows(reinterpret_cast<const char*>(x), &rest.pairs[b], m.elemStart[e + 1] - b, S[0][l], S[1][l], S[2][l]);
    }
    for (int j = 0; j < 3; ++j) transpose(S[j][0], S[j][1], S[j][2], S[j][3]);
    const ElementConstantGroup& g = rest.groups[e0 / L];
    const VolumeBasisGroup& bg = basis[e0 / L];
    d4 P[9], M[9], Ah[9];
    for (int k = 0; k < 9; ++k) P[k] = load4(vg.shape[k]), M[k] = load4(bg.M[k]);
    // A / h = sum x P^T - c (sum P)^T, c = sum x / n; F = (A / h) shape.
    for (int j = 0; j < 3; ++j) {
      const d4 c = S[j][3] * load4(g.invCount);
      for (int k = 0; k < 3; ++k) Ah[3 * j + k] = S[j][k] - c * load4(g.sumLattice[k]);
    }
    d4 F[9], Y[9];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) F[3 * r + c] = Ah[3 * r] * P[c] + Ah[3 * r + 1] * P[3 + c] + Ah[3 * r + 2] * P[6 + c];
    // The rotation refreshed by one Newton step of the polar fit from the step's M:
    // Y = M^T F, M' = M (I + [w]x) with (tr Y I - sym Y) w = 2 axial(skew Y), so that M'^T F is
    // symmetric to second order and the forces keep their zero torque.
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) Y[3 * r + c] = M[r] * F[c] + M[3 + r] * F[3 + c] + M[6 + r] * F[6 + c];
    const d4 half = splat(0.5);
    const d4 ax = half * (Y[7] - Y[5]), ay = half * (Y[2] - Y[6]), az = half * (Y[3] - Y[1]);
    d4 w[3];
    if (m.dim == 2) {
      const d4 den = Y[0] + Y[4];
      w[0] = w[1] = zero, w[2] = select(abs(den) > splat(1e-12), (az + az) / den, zero);
    } else {
      const d4 t = Y[0] + Y[4] + Y[8];
      const d4 k00 = t - Y[0], k11 = t - Y[4], k22 = t - Y[8];
      const d4 k01 = zero - half * (Y[1] + Y[3]), k02 = zero - half * (Y[2] + Y[6]), k12 = zero - half * (Y[5] + Y[7]);
      // The adjugate of the symmetric K.
      const d4 c00 = k11 * k22 - k12 * k12, c01 = k02 * k12 - k01 * k22, c02 = k01 * k12 - k02 * k11;
      const d4 c11 = k00 * k22 - k02 * k02, c12 = k01 * k02 - k00 * k12, c22 = k00 * k11 - k01 * k01;
      const d4 det = k00 * c00 + k01 * c01 + k02 * c02;
      const m4 ok = abs(det) > splat(1e-12) * abs(t * t * t);  // else (degenerate, inverted) no refresh
      const d4 inv = select(ok, splat(2) / det, zero);
      w[0] = inv * (c00 * ax + c01 * ay + c02 * az);
      w[1] = inv * (c01 * ax + c11 * ay + c12 * az);
      w[2] = inv * (c02 * ax + c12 * ay + c22 * az);
    }
    d4 Mw[9];  // M (I + [w]x): column c gains M [w]x e_c
    for (int r = 0; r < 3; ++r) {
      const d4 m0 = M[3 * r], m1 = M[3 * r + 1], m2 = M[3 * r + 2];
      Mw[3 * r] = m0 + m1 * w[2] - m2 * w[1];
      Mw[3 * r + 1] = m1 - m0 * w[2] + m2 * w[0];
      Mw[3 * r + 2] = m2 + m0 * w[1] - m1 * w[0];
    }
    d4 tr = zero;
    for (int k = 0; k < 9; ++k) tr += Mw[k] * F[k];
    const d4 s = kappa * (D - tr);  // -(kappa / h) e_v
    d4 Fr[4][4];                    // Fr[column][row before the transpose]
    for (int r = 0; r < 3; ++r) {
      d4 hr[3];
      for (int c = 0; c < 3; ++c) hr[c] = s * (Mw[3 * r] * P[c] + Mw[3 * r + 1] * P[3 + c] + Mw[3 * r + 2] * P[6 + c]);
      Fr[0][r] = hr[0], Fr[1][r] = hr[1], Fr[2][r] = hr[2];
      Fr[3][r] = zero - (hr[0] * (load4(g.restCentroid[0]) + load4(g.meanRestOffset[0])) +
                         hr[1] * (load4(g.restCentroid[1]) + load4(g.meanRestOffset[1])) +
                         hr[2] * (load4(g.restCentroid[2]) + load4(g.meanRestOffset[2])));
    }
    Fr[0][3] = Fr[1][3] = Fr[2][3] = Fr[3][3] = zero;
    for (int col = 0; col < 4; ++col) transpose(Fr[col][0], Fr[col][1], Fr[col][2], Fr[col][3]);
    for (int l = 0; l < lanes; ++l) {
      ElementFrame& f = frames[e0 + l];
      store4(f.c0, Fr[0][l]), store4(f.c1, Fr[1][l]), store4(f.c2, Fr[2][l]), store4(f.t, Fr[3][l]);
    }
  }
}

}  // namespace gradel
