#include "gradel/display_normals.h"

#include <algorithm>
#include <cmath>

namespace gradel {

Real displayNormalSigma(const VoxelVolume& volume) {
  const int n = std::max({volume.nx(), volume.ny(), volume.nz()});
  return std::max(1.0, 0.5 * std::sqrt(Real(n)));
}

namespace {

// One box average of half-width r along axis `a` of the n[0] x n[1] x n[2] grid (zero outside),
// by a running sum: O(1) per sample whatever r.
void boxPass(std::vector<float>& f, std::vector<float>& tmp, const int n[3], int a, int r) {
  const size_t stride[3] = {1, size_t(n[0]), size_t(n[0]) * size_t(n[1])};
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  const float scale = 1.0f / float(2 * r + 1);
  tmp.resize(size_t(n[a]));
  for (int j = 0; j < n[b]; ++j)
    for (int k = 0; k < n[c]; ++k) {
      const size_t base = size_t(j) * stride[b] + size_t(k) * stride[c];
      auto at = [&](int i) { return i < 0 || i >= n[a] ? 0.0f : f[base + size_t(i) * stride[a]]; };
      double sum = 0;
      for (int i = -r; i <= r; ++i) sum += at(i);
      for (int i = 0; i < n[a]; ++i) {
        tmp[size_t(i)] = float(sum) * scale;
        sum += at(i + r + 1) - at(i - r);
      }
      for (int i = 0; i < n[a]; ++i) f[base + size_t(i) * stride[a]] = tmp[size_t(i)];
    }
}

}  // namespace

std::vector<Vec3> fieldNormals(const VoxelVolume& volume, const std::vector<Vec3>& points, Real sigma) {
  if (volume.dim() != 3) throw InputError("fieldNormals: needs a 3D volume");
  // Three boxes of width w have variance 3 (w^2 - 1) / 12 = sigma^2.
  const int r = std::max(1, int(std::lround((std::sqrt(4 * sigma * sigma + 1) - 1) / 2)));
  const int pad = 3 * r + 2;
  const int n[3] = {volume.nx() + 2 * pad, volume.ny() + 2 * pad, volume.nz() + 2 * pad};
  auto id = [&](int i, int j, int k) { return size_t(i) + size_t(n[0]) * (size_t(j) + size_t(n[1]) * size_t(k)); };
  std::vector<float> f(size_t(n[0]) * size_t(n[1]) * size_t(n[2]), 0.0f), tmp;
  for (int k = 0; k < volume.nz(); ++k)
    for (int j = 0; j < volume.ny(); ++j)
      for (int i = 0; i < volume.nx(); ++i)
        if (volume.at(i, j, k)) f[id(i + pad, j + pad, k + pad)] = 1.0f;
  for (int pass = 0; pass < 3; ++pass)
    for (int a = 0; a < 3; ++a) boxPass(f, tmp, n, a, r);

  // Sample (i, j, k) of f is the centre of voxel (i - pad, ...): lattice point (i - pad + 0.5, ...).
  auto gradientAt = [&](int i, int j, int k) {  // central differences, clamped to the grid
    auto v = [&](int x, int y, int z) {
      x = std::clamp(x, 0, n[0] - 1), y = std::clamp(y, 0, n[1] - 1), z = std::clamp(z, 0, n[2] - 1);
      return Real(f[id(x, y, z)]);
    };
    return Vec3(v(i + 1, j, k) - v(i - 1, j, k), v(i, j + 1, k) - v(i, j - 1, k), v(i, j, k + 1) - v(i, j, k - 1));
  };
  std::vector<Vec3> out(points.size(), Vec3::Zero());
  for (size_t p = 0; p < points.size(); ++p) {
    const Vec3 q = points[p] + Vec3::Constant(Real(pad) - 0.5);  // in sample indices
    const int i0 = int(std::floor(q.x())), j0 = int(std::floor(q.y())), k0 = int(std::floor(q.z()));
    const Real fx = q.x() - i0, fy = q.y() - j0, fz = q.z() - k0;
    Vec3 g = Vec3::Zero();
    for (int c = 0; c < 8; ++c) {
      const int dx = c & 1, dy = c >> 1 & 1, dz = c >> 2 & 1;
      const Real w = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz);
      if (w != 0) g += w * gradientAt(i0 + dx, j0 + dy, k0 + dz);
    }
    const Real len = g.norm();
    if (len > 1e-12) out[p] = -g / len;
  }
  return out;
}

std::vector<Vec3> carryNormals(const std::vector<Vec3>& now, const std::vector<Vec3>& rest,
                               const std::vector<Vec3>& restField) {
  std::vector<Vec3> out(now.size());
  for (size_t v = 0; v < now.size(); ++v) {
    const Vec3 &a = rest[v], &b = now[v], &g = restField[v];
    const Real c = a.dot(b);
    if (g.squaredNorm() == 0 || c < -0.85) {
      out[v] = b;
      continue;
    }
    // Rodrigues with k = a x b (|k| = sin): g c + k x g + k (k . g) / (1 + c).
    const Vec3 k = a.cross(b);
    out[v] = (g * c + k.cross(g) + k * (k.dot(g) / (1 + c))).normalized();
  }
  return out;
}

}  // namespace gradel
