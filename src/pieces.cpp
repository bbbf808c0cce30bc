// A body's connected pieces and the body split into them (pieces.h).
#include "gradel/pieces.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "carve_cells.h"

namespace gradel {

namespace {

using namespace carve_cells;

uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

// Union-find over the vertices, joining each element's: parent links (the lowest id of a piece is its root).
std::vector<uint32_t> joinElements(const Layout& layout) {
  std::vector<uint32_t> parent(layout.numVertices());
  std::iota(parent.begin(), parent.end(), 0u);
  for (size_t e = 0; e < layout.numElements(); ++e) {
    uint32_t first = findRoot(parent, layout.elemVerts[layout.elemStart[e]]);
    for (uint32_t p = layout.elemStart[e] + 1; p < layout.elemStart[e + 1]; ++p) {
      const uint32_t r = findRoot(parent, layout.elemVerts[p]);
      if (r == first) continue;
      parent[std::max(r, first)] = std::min(r, first);  // the lower id stays the root
      first = std::min(r, first);
    }
  }
  return parent;
}

// Whether every vertex reaches root 0: the body is one piece (the common case of a carving event,
// decided without the voxel passes of findPieces).
bool onePiece(const Layout& layout) {
  std::vector<uint32_t> parent = joinElements(layout);
  for (uint32_t v = 0; v < parent.size(); ++v)
    if (findRoot(parent, v) != 0) return false;
  return true;
}

}  // namespace

BodyPieces findPieces(const Layout& layout, const VoxelVolume& volume) {
  if (volume.dims() != layout.dims) throw std::invalid_argument("findPieces: the volume is not the layout's");
  const size_t V = layout.numVertices();
  std::vector<uint32_t> parent = joinElements(layout);
  // Components in order of their first voxel (storage order), then sorted largest first.
  const std::vector<int32_t> owner = voxelOwners(layout, volume);
  std::vector<int32_t> rootPiece(V, -1);
  std::vector<size_t> voxels, firstVoxel;
  std::vector<int32_t> voxelComponent(volume.size(), -1);
  for (size_t q = 0; q < volume.size(); ++q) {
    if (owner[q] < 0) continue;
    const uint32_t r = findRoot(parent, layout.elemVerts[layout.elemStart[size_t(owner[q])]]);
    if (rootPiece[r] < 0) rootPiece[r] = int32_t(voxels.size()), voxels.push_back(0), firstVoxel.push_back(q);
    voxelComponent[q] = rootPiece[r];
    ++voxels[size_t(rootPiece[r])];
  }
  std::vector<int32_t> order(voxels.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return voxels[size_t(a)] > voxels[size_t(b)]; });
  std::vector<int32_t> rank(order.size());
  for (size_t k = 0; k < order.size(); ++k) rank[size_t(order[k])] = int32_t(k);
  BodyPieces out;
  out.voxels.resize(order.size());
  for (size_t k = 0; k < order.size(); ++k) out.voxels[k] = voxels[size_t(order[k])];
  out.voxelPiece.assign(volume.size(), -1);
  for (size_t q = 0; q < volume.size(); ++q)
    if (voxelComponent[q] >= 0) out.voxelPiece[q] = rank[size_t(voxelComponent[q])];
  out.vertexPiece.resize(V);
  for (size_t v = 0; v < V; ++v) {
    const int32_t c = rootPiece[findRoot(parent, uint32_t(v))];
    if (c < 0) throw std::logic_error("findPieces: a vertex of no element");
    out.vertexPiece[v] = rank[size_t(c)];
  }
  return out;
}

std::vector<BodyPiece> splitBody(const CarveInput& b) {
  checkInput(b);
  const VoxelVolume& volume = *b.volume;
  const Layout& layout = *b.layout;
  const RestModel& model = *b.model;
  if (volume.dims() == layout.dims && onePiece(layout)) return {};
  const BodyPieces pieces = findPieces(layout, volume);
  if (pieces.count() <= 1) return {};
  const std::vector<int32_t> owner = voxelOwners(layout, volume);
  std::vector<BodyPiece> out(pieces.count());
  for (size_t k = 0; k < out.size(); ++k) {
    BodyPiece& p = out[k];
    p.volume = volume;
    const auto& n = volume.dims();
    for (int z = 0; z < n[2]; ++z)
      for (int y = 0; y < n[1]; ++y)
        for (int x = 0; x < n[0]; ++x) {
          const int32_t piece = pieces.voxelPiece[volume.index(x, y, z)];
          if (piece >= 0 && size_t(piece) != k) p.volume.set(x, y, z, false);
        }
    p.layout = buildLayout(p.volume, layout.kind);
    auto m = std::make_shared<RestModel>(buildRestModel(p.layout, p.volume, model.material, model.origin));
    // The piece's momentum: that of the body's vertices it holds (the pieces share none).
    Vec3 target = Vec3::Zero();
    for (size_t v = 0; v < model.numVertices(); ++v)
      if (size_t(pieces.vertexPiece[v]) == k) target += model.mass[v] * b.velocities[v];
    Transferred t = transferState(layout, owner, volume, b.positions, b.velocities, b.rotations, p.volume, p.layout,
                                  *m, target);
    takeTransferred(p, std::move(t));
    p.model = std::move(m);
  }
  return out;
}

}  // namespace gradel
