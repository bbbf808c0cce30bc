#include "gradel/isosurface.h"

#include <algorithm>
#include <string>
#include <unordered_map>

#include "gradel/display_normals.h"
#include "gradel/surface.h"

namespace gradel {

namespace {

// Kuhn triangulation of the unit cube (corner c = x + 2y + 4z): six tetrahedra around the
// diagonal 0-7; every face diagonal is cut the same way in neighbouring cubes.
constexpr int kTets[6][4] = {{0, 1, 3, 7}, {0, 3, 2, 7}, {0, 2, 6, 7}, {0, 6, 4, 7}, {0, 4, 5, 7}, {0, 5, 1, 7}};
constexpr float kIso = 0.5f;
constexpr int kPad = 2;  // empty voxel layers around the grid: one for the blur, one for the closing level set

}  // namespace

TriangleMesh isosurface(const VoxelVolume& volume, const Vec3& origin, int step) {
  if (volume.dim() != 3) throw InputError("isosurface: needs a 3D volume");
  if (volume.countFilled() == 0) throw InputError("isosurface: empty volume");
  if (step < 1) throw InputError("isosurface: step " + std::to_string(step) + " (must be >= 1)");
  const int s = step;
  // Sample point (i, j, k) is the centre of coarse voxel (i - kPad, j - kPad, k - kPad), the
  // block of s^3 fine voxels starting at s * (i - kPad, ...).
  const int nx = (volume.nx() + s - 1) / s + 2 * kPad, ny = (volume.ny() + s - 1) / s + 2 * kPad,
            nz = (volume.nz() + s - 1) / s + 2 * kPad;
  auto at = [&](int i, int j, int k) { return size_t(i) + size_t(nx) * (size_t(j) + size_t(ny) * size_t(k)); };

  // Filled fine voxels in [0, i) x [0, j) x [0, k) (a summed-volume table; outside the volume is
  // empty), so a box count costs eight look-ups at any step.
  const int fx = volume.nx(), fy = volume.ny(), fz = volume.nz();
  std::vector<int32_t> sum(size_t(fx + 1) * size_t(fy + 1) * size_t(fz + 1), 0);
  auto sat = [&](int i, int j, int k) -> int32_t& {
    return sum[size_t(i) + size_t(fx + 1) * (size_t(j) + size_t(fy + 1) * size_t(k))];
  };
  for (int k = 1; k <= fz; ++k)
    for (int j = 1; j <= fy; ++j)
      for (int i = 1; i <= fx; ++i)
        sat(i, j, k) = int32_t(volume.at(i - 1, j - 1, k - 1)) + sat(i - 1, j, k) + sat(i, j - 1, k) +
                       sat(i, j, k - 1) - sat(i - 1, j - 1, k) - sat(i - 1, j, k - 1) - sat(i, j - 1, k - 1) +
                       sat(i - 1, j - 1, k - 1);
  auto boxCount = [&](int x0, int y0, int z0, int x1, int y1, int z1) {  // filled in [x0, x1) x ... (clamped)
    x0 = std::clamp(x0, 0, fx), x1 = std::clamp(x1, 0, fx), y0 = std::clamp(y0, 0, fy), y1 = std::clamp(y1, 0, fy);
    z0 = std::clamp(z0, 0, fz), z1 = std::clamp(z1, 0, fz);
    if (x0 >= x1 || y0 >= y1 || z0 >= z1) return 0;
    return sat(x1, y1, z1) - sat(x0, y1, z1) - sat(x1, y0, z1) - sat(x1, y1, z0) + sat(x0, y0, z1) + sat(x0, y1, z0) +
           sat(x1, y0, z0) - sat(x0, y0, z0);
  };
  // The field at a sample: the filled share of the 3x3x3 coarse voxels around it (3s fine voxels
  // a side; at step 1 the 3x3x3 box average of the voxels).
  // 27 s^3 voxels: count / 27 is never exactly the 0.5 level at odd s; at even s half a voxel
  // is added so it is not either (a sample on the level would put crossings on sample points).
  const float boxVolume = float(27 * s * s * s), offset = s % 2 == 0 ? 0.5f : 0.0f;
  std::vector<float> field(size_t(nx) * size_t(ny) * size_t(nz), 0.0f);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const int x0 = s * (i - kPad - 1), y0 = s * (j - kPad - 1), z0 = s * (k - kPad - 1);
        field[at(i, j, k)] = (float(boxCount(x0, y0, z0, x0 + 3 * s, y0 + 3 * s, z0 + 3 * s)) + offset) / boxVolume;
      }

  TriangleMesh mesh;
  std::unordered_map<uint64_t, uint32_t> edgeVertex;  // lattice edge (two sample ids) -> mesh vertex
  auto samplePos = [&](size_t id) {
    const int i = int(id % size_t(nx)), j = int(id / size_t(nx) % size_t(ny)), k = int(id / (size_t(nx) * size_t(ny)));
    return Vec3(s * (i - kPad + 0.5), s * (j - kPad + 0.5), s * (k - kPad + 0.5));
  };
  auto crossing = [&](size_t a, size_t b) {
    if (a > b) std::swap(a, b);
    const uint64_t key = uint64_t(a) * uint64_t(field.size()) + b;
    auto [it, added] = edgeVertex.emplace(key, uint32_t(mesh.vertices.size()));
    if (added) {
      const double t = (kIso - field[a]) / (field[b] - field[a]);
      mesh.vertices.push_back(origin + volume.voxelSize() * (samplePos(a) + t * (samplePos(b) - samplePos(a))));
    }
    return it->second;
  };
  // Adds a triangle on the crossings, turned so that it faces from `inside` towards `outside`.
  auto emit = [&](uint32_t p, uint32_t q, uint32_t r, const Vec3& inside, const Vec3& outside) {
    const Vec3 n = (mesh.vertices[q] - mesh.vertices[p]).cross(mesh.vertices[r] - mesh.vertices[p]);
    if (n.squaredNorm() == 0) return;
    if (n.dot(outside - inside) < 0) std::swap(q, r);
    mesh.triangles.push_back({p, q, r});
  };

  for (int k = 0; k + 1 < nz; ++k)
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) {
        size_t corner[8];
        for (int c = 0; c < 8; ++c) corner[c] = at(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1));
        for (const auto& tet : kTets) {
          std::vector<size_t> in, out;
          for (int v : tet) (field[corner[v]] > kIso ? in : out).push_back(corner[v]);
          if (in.empty() || out.empty()) continue;
          Vec3 ci = Vec3::Zero(), co = Vec3::Zero();
          for (size_t s : in) ci += samplePos(s) / Real(in.size());
          for (size_t s : out) co += samplePos(s) / Real(out.size());
          const Vec3 inside = origin + volume.voxelSize() * ci, outside = origin + volume.voxelSize() * co;
          if (in.size() == 1 || out.size() == 1) {
            const std::vector<size_t>& lone = in.size() == 1 ? in : out;
            const std::vector<size_t>& rest = in.size() == 1 ? out : in;
            emit(crossing(lone[0], rest[0]), crossing(lone[0], rest[1]), crossing(lone[0], rest[2]), inside, outside);
          } else {
            // Two in, two out: the crossings form a quad in0-out0, in0-out1, in1-out1, in1-out0.
            const uint32_t a = crossing(in[0], out[0]), b = crossing(in[0], out[1]), c = crossing(in[1], out[1]),
                           d = crossing(in[1], out[0]);
            emit(a, b, c, inside, outside);
            emit(a, c, d, inside, outside);
          }
        }
      }
  // Normals from the occupancy smoothed wider than the surface itself (display_normals.h): no
  // terraces; the mesh's own where that field is flat.
  mesh.normals = vertexNormals(mesh.vertices, mesh.triangles);
  std::vector<Vec3> lattice(mesh.vertices.size());
  for (size_t v = 0; v < lattice.size(); ++v) lattice[v] = (mesh.vertices[v] - origin) / volume.voxelSize();
  const std::vector<Vec3> smoothed = fieldNormals(volume, lattice, displayNormalSigma(volume));
  for (size_t v = 0; v < smoothed.size(); ++v)
    if (smoothed[v].squaredNorm() > 0) mesh.normals[v] = smoothed[v];
  return mesh;
}

}  // namespace gradel
