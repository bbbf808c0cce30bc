// Four doubles in one register (GCC / clang vector extensions): AVX2 where the build has it,
// plain scalar code elsewhere. A Vec3 travels as (x, y, z, 0). Used by the hot kernels only
// (element_stage.cpp, rotation_fit.cpp, step_explicit.cpp).
#pragma once

#include <cmath>
#include <cstdint>
#if defined(__AVX__)
#include <immintrin.h>
#endif

#include "gradel/types.h"

namespace gradel::simd {

using d4 = Real __attribute__((vector_size(32)));
using m4 = long long __attribute__((vector_size(32)));  ///< Lane masks: all ones or zero.

inline d4 splat(Real v) { return d4{v, v, v, v}; }
inline d4 load4(const Real* p) {
  d4 r;
  __builtin_memcpy(&r, p, sizeof r);
  return r;
}
inline void store4(Real* p, d4 v) { __builtin_memcpy(p, &v, sizeof v); }

/// (x, y, z, 0) of a Vec3, without reading past it.
inline d4 loadVec3(const Vec3& v) {
#if defined(__AVX__)
  return (d4)_mm256_maskload_pd(v.data(), _mm256_setr_epi64x(-1, -1, -1, 0));
#else
  return d4{v.x(), v.y(), v.z(), 0};
#endif
}
/// Four floats as doubles.
inline d4 loadFloat4(const float* p) {
#if defined(__AVX__)
  return (d4)_mm256_cvtps_pd(_mm_loadu_ps(p));
#else
  return d4{p[0], p[1], p[2], p[3]};
#endif
}
/// Writes lanes 0-2 into a Vec3.
inline void storeVec3(Vec3& v, d4 a) {
#if defined(__AVX__)
  const __m256d r = (__m256d)a;
  _mm_storeu_pd(v.data(), _mm256_castpd256_pd128(r));
  _mm_store_sd(v.data() + 2, _mm256_extractf128_pd(r, 1));
#else
  v = Vec3(a[0], a[1], a[2]);
#endif
}

/// a where m is set, else b (one vblendvpd with AVX; the masks' lanes are all ones or zero).
inline d4 select(m4 m, d4 a, d4 b) {
#if defined(__AVX__)
  return (d4)_mm256_blendv_pd((__m256d)b, (__m256d)a, (__m256d)m);
#else
  return (d4)(((m4)a & m) | ((m4)b & ~m));
#endif
}
inline d4 abs(d4 a) { return (d4)((m4)a & ~(m4)splat(-0.0)); }  ///< Clears the sign bits.
inline d4 sqrt(d4 a) {
#if defined(__AVX__)
  return (d4)_mm256_sqrt_pd((__m256d)a);
#else
  for (int l = 0; l < 4; ++l) a[l] = std::sqrt(a[l]);
  return a;
#endif
}
/// Lane-wise min / max (with a NaN lane the result's lane is b's).
inline d4 min(d4 a, d4 b) {
#if defined(__AVX__)
  return (d4)_mm256_min_pd((__m256d)a, (__m256d)b);
#else
  return select(a < b, a, b);
#endif
}
inline d4 max(d4 a, d4 b) {
#if defined(__AVX__)
  return (d4)_mm256_max_pd((__m256d)a, (__m256d)b);
#else
  return select(a > b, a, b);
#endif
}
/// No lane set. One vptest with AVX (the lane-by-lane OR took four extracts and three ORs: the
/// rotation fit asks this five times an iteration).
inline bool none(m4 m) {
#if defined(__AVX__)
  return _mm256_testz_si256((__m256i)m, (__m256i)m);
#else
  return !(m[0] | m[1] | m[2] | m[3]);
#endif
}

/// Four int16 converted to doubles (exact).
inline d4 loadInt16x4(const int16_t* p) {
#if defined(__AVX2__)
  return (d4)_mm256_cvtepi32_pd(_mm_cvtepi16_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p))));
#else
  return d4{Real(p[0]), Real(p[1]), Real(p[2]), Real(p[3])};
#endif
}

/// Four int8 converted to doubles (exact).
inline d4 loadInt8x4(const int8_t* p) {
#if defined(__AVX2__)
  int32_t v;
  __builtin_memcpy(&v, p, sizeof v);
  return (d4)_mm256_cvtepi32_pd(_mm_cvtepi8_epi32(_mm_cvtsi32_si128(v)));
#else
  return d4{Real(p[0]), Real(p[1]), Real(p[2]), Real(p[3])};
#endif
}

/// p[l + 1] - p[l] for l = 0..3 as doubles (exact below 2^31): the counts of four CSR rows.
inline d4 loadCountDifference(const uint32_t* p) {
#if defined(__AVX2__)
  const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
  const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 1));
  return (d4)_mm256_cvtepi32_pd(_mm_sub_epi32(b, a));
#else
  return d4{Real(p[1] - p[0]), Real(p[2] - p[1]), Real(p[3] - p[2]), Real(p[4] - p[3])};
#endif
}

/// (a[3], b[3], c[3], 0).
inline d4 laneThrees(d4 a, d4 b, d4 c) {
#if defined(__AVX__)
  const __m256d ab = _mm256_unpackhi_pd((__m256d)a, (__m256d)b);              // a1 b1 a3 b3
  const __m256d c0 = _mm256_unpackhi_pd((__m256d)c, _mm256_setzero_pd());     // c1 0 c3 0
  return (d4)_mm256_permute2f128_pd(ab, c0, 0x31);
#else
  return d4{a[3], b[3], c[3], 0};
#endif
}

/// 4x4 transpose in place: afterwards a holds the old lane 0 of a, b, c, d, and so on.
inline void transpose(d4& a, d4& b, d4& c, d4& d) {
#if defined(__AVX__)
  const __m256d t0 = _mm256_unpacklo_pd((__m256d)a, (__m256d)b), t1 = _mm256_unpackhi_pd((__m256d)a, (__m256d)b);
  const __m256d t2 = _mm256_unpacklo_pd((__m256d)c, (__m256d)d), t3 = _mm256_unpackhi_pd((__m256d)c, (__m256d)d);
  a = (d4)_mm256_permute2f128_pd(t0, t2, 0x20), b = (d4)_mm256_permute2f128_pd(t1, t3, 0x20);
  c = (d4)_mm256_permute2f128_pd(t0, t2, 0x31), d = (d4)_mm256_permute2f128_pd(t1, t3, 0x31);
#else
  const d4 r[4] = {a, b, c, d};
  for (int l = 0; l < 4; ++l) a[l] = r[l][0], b[l] = r[l][1], c[l] = r[l][2], d[l] = r[l][3];
#endif
}

}  // namespace gradel::simd
