#include "gradel/isosurface.h"

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

TriangleMesh isosurface(const VoxelVolume& volume, const Vec3& origin) {
  if (volume.dim() != 3) throw InputError("isosurface: needs a 3D volume");
  if (volume.countFilled() == 0) throw InputError("isosurface: empty volume");
  const int nx = volume.nx() + 2 * kPad, ny = volume.ny() + 2 * kPad, nz = volume.nz() + 2 * kPad;
  auto at = [&](int i, int j, int k) { return size_t(i) + size_t(nx) * (size_t(j) + size_t(ny) * size_t(k)); };

  // Sample point (i, j, k) is the centre of voxel (i - kPad, j - kPad, k - kPad).
  std::vector<float> field(size_t(nx) * size_t(ny) * size_t(nz), 0.0f);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        int filled = 0;
        for (int dz = -1; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) filled += volume.at(i - kPad + dx, j - kPad + dy, k - kPad + dz);
        field[at(i, j, k)] = float(filled) / 27.0f;  // k/27 is never exactly the 0.5 level
      }

  TriangleMesh mesh;
  std::unordered_map<uint64_t, uint32_t> edgeVertex;  // lattice edge (two sample ids) -> mesh vertex
  auto samplePos = [&](size_t id) {
    const int i = int(id % size_t(nx)), j = int(id / size_t(nx) % size_t(ny)), k = int(id / (size_t(nx) * size_t(ny)));
    return Vec3(i - kPad + 0.5, j - kPad + 0.5, k - kPad + 0.5);
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
