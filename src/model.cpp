#include "gradel/model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "gradel/element.h"
#include "gradel/settings_check.h"
#include "plane.h"

namespace gradel {

namespace {

// Step 1: rest positions, origin + lattice * h.
void placeVertices(const Layout& layout, const Vec3& origin, RestModel& m) {
  m.restPositions.resize(layout.numVertices());
  for (size_t i = 0; i < layout.numVertices(); ++i)
    m.restPositions[i] = origin + layout.vertices[i].cast<Real>() * layout.voxelSize;
}

// Step 2a: the materials table, one entry per label of the layout (ascending), and each
// element's entry.
void assignMaterials(const Layout& layout, RestModel& m) {
  const size_t E = layout.numElements();
  const bool labelled = layout.label.size() == E;  // a hand-made Layout may carry no labels: all 1
  std::vector<uint8_t> seen(65536, 0);
  if (labelled)
    for (uint16_t l : layout.label) seen[l] = 1;
  else
    seen[1] = 1;
  std::vector<uint16_t> index(65536, 0);
  for (size_t l = 1; l < seen.size(); ++l)
    if (seen[l]) {
      index[l] = uint16_t(m.materials.size());
      m.materials.push_back(regionMaterial(m.material, uint16_t(l)));
      m.materialLabel.push_back(uint16_t(l));
    }
  m.elementMaterial.resize(E);
  for (size_t e = 0; e < E; ++e) m.elementMaterial[e] = index[labelled ? layout.label[e] : 1];
}

// Step 2b: lumped masses (material.h's rules, each element's cells with its own density), their
// inverses and the total.
// Per-vertex damping weights (model.h, RestModel::dampingOwn): each region's share of a vertex's
// weight, accumulated in lumpMasses when some region sets its own damping rate.
class DampingWeights {
 public:
  DampingWeights(const RestModel& m, size_t V) : m_(m) {
    for (const MaterialSettings& r : m.materials) active_ = active_ || r.damping.has_value();
    if (!active_) return;
    weight_.assign(V, 0), own_.assign(V, 0), plain_.assign(V, 0), first_.assign(V, kNone), mixed_.assign(V, 0);
  }
  void add(uint32_t v, Real w, uint16_t material) {
    if (!active_) return;
    const std::optional<Real>& c = m_.materials[material].damping;
    weight_[v] += w;
    if (c)
      own_[v] += w * *c;
    else
      plain_[v] += w;
    if (first_[v] == kNone) first_[v] = material;
    const std::optional<Real>& c0 = m_.materials[first_[v]].damping;
    if (c0 != c) mixed_[v] = 1;
  }
  // A vertex of one rate (or of regions that all take the simulation's) gets it exactly.
  void finish(RestModel& m) const {
    if (!active_) return;
    const size_t V = weight_.size();
    m.dampingOwn.assign(V, 0), m.dampingDefaultShare.assign(V, 1);
    for (size_t v = 0; v < V; ++v) {
      if (first_[v] == kNone) continue;
      const std::optional<Real>& c = m.materials[first_[v]].damping;
      if (!mixed_[v])
        m.dampingOwn[v] = c.value_or(0), m.dampingDefaultShare[v] = c ? 0 : 1;
      else
        m.dampingOwn[v] = own_[v] / weight_[v], m.dampingDefaultShare[v] = plain_[v] / weight_[v];
    }
  }

 private:
  static constexpr uint16_t kNone = 0xffff;
  const RestModel& m_;
  bool active_ = false;
  std::vector<Real> weight_, own_, plain_;
  std::vector<uint16_t> first_;
  std::vector<uint8_t> mixed_;
};

void lumpMasses(const Layout& layout, RestModel& m) {
  const int D = layout.dim;
  const size_t V = layout.numVertices();
  DampingWeights damping(m, V);
  if (m.material.scaling == Scaling::Paper && m.materials.size() == 1) {
    m.mass.assign(V, paperVertexMass(m.materials[0], layout.voxelSize));
    for (uint32_t v = 0; v < V; ++v) damping.add(v, 1, 0);
  } else if (m.material.scaling == Scaling::Paper) {
    // One voxel's mass per vertex; a vertex on a border between regions takes the lightest of
    // the elements that own it (the shorter period, so dt = auto stays on the safe side).
    m.mass.assign(V, std::numeric_limits<Real>::infinity());
    for (size_t e = 0; e < layout.numElements(); ++e) {
      const Real mv = paperVertexMass(m.materials[m.elementMaterial[e]], layout.voxelSize);
      for (uint32_t p = layout.elemStart[e]; p < layout.elemStart[e + 1]; ++p)
        if (layout.pairIsOwn[p]) {
          m.mass[layout.elemVerts[p]] = std::min(m.mass[layout.elemVerts[p]], mv);
          damping.add(layout.elemVerts[p], mv, m.elementMaterial[e]);
        }
    }
  } else {
    // Each filled cell (the whole block for a full element) gives its mass in equal parts to
    // its corners; those are always model vertices (an element's own vertices).
    m.mass.assign(V, 0.0);
    const int corners = D == 3 ? 8 : 4;
    for (size_t e = 0; e < layout.numElements(); ++e) {
      const bool full = layout.isFull(e);
      const int cellSize = layout.cellSize[e], cs = full ? 2 * cellSize : cellSize;
      const Real cornerMass = cellCornerMass(m.materials[m.elementMaterial[e]], layout.voxelSize, cs, D);
      const int cells = D == 3 ? 8 : 4;
      // The element's vertices at the 3^D points of its block at its cell size (slot a_x + 3 a_y
      // + 9 a_z, a in {0, 1, 2}): the corners of its cells are among them (its own vertices).
      uint32_t slot[27];
      std::fill(slot, slot + 27, Layout::kNoVertex);
      for (uint32_t q = layout.elemStart[e]; q < layout.elemStart[e + 1]; ++q) {
        const Int3 r = layout.vertices[layout.elemVerts[q]] - layout.origin[e];
        if (r.x() % cellSize || r.y() % cellSize || r.z() % cellSize || (r.array() < 0).any() ||
            (r.array() > 2 * cellSize).any())
          continue;
        const Int3 a = r / cellSize;
        slot[a.x() + 3 * a.y() + 9 * a.z()] = layout.elemVerts[q];
      }
      for (int c = 0; c < (full ? 1 : cells); ++c) {
        if (!full && !(layout.cellMask[e] >> c & 1)) continue;
        const Int3 lo = full ? Int3(0, 0, 0) : Int3(c & 1, (c >> 1) & 1, (c >> 2) & 1);
        for (int k = 0; k < corners; ++k) {
          const Int3 a = lo + Int3(k & 1, (k >> 1) & 1, D == 3 ? (k >> 2) & 1 : 0) * (full ? 2 : 1);
          const uint32_t id = slot[a.x() + 3 * a.y() + 9 * a.z()];
          if (id == Layout::kNoVertex) throw std::logic_error("buildRestModel: a cell corner is not a model vertex");
          m.mass[id] += cornerMass;
          damping.add(id, cornerMass, m.elementMaterial[e]);
        }
      }
    }
  }
  damping.finish(m);
  m.invMass.resize(V);
  m.totalMass = 0;
  for (size_t i = 0; i < V; ++i) {
    if (!(m.mass[i] > 0)) throw std::logic_error("buildRestModel: a vertex has no mass");
    m.invMass[i] = 1.0 / m.mass[i];
    m.totalMass += m.mass[i];
  }
}

// Step 3: per element, the rest offsets R0 (from the rest centroid), the size, the stiffness
// (material.h) and the smallest element period (sec. 3.4).
void buildElements(const Layout& layout, RestModel& m) {
  const size_t E = layout.numElements();
  m.elemStart = layout.elemStart;
  m.elemVerts = layout.elemVerts;
  m.level = layout.level;
  m.restCentroids.resize(E);
  m.stiffness.resize(E);
  std::vector<Vec3> R0;
  m.size.resize(E);
  Real smallest = std::numeric_limits<Real>::infinity();
  for (size_t e = 0; e < E; ++e) {
    const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    Vec3 c = Vec3::Zero();
    for (uint32_t p = b; p < b + n; ++p) c += m.restPositions[m.elemVerts[p]];
    c /= Real(n);
    m.restCentroids[e] = c;
    Real minMass = std::numeric_limits<Real>::infinity();
    for (uint32_t p = b; p < b + n; ++p) minMass = std::min(minMass, m.mass[m.elemVerts[p]]);
    m.restOffsets(e, R0);
    m.size[e] = (layout.kind == LayoutKind::Voxel ? 1 : 2) * layout.cellSize[e] * layout.voxelSize;
    m.stiffness[e] = elementStiffness(m.materials[m.elementMaterial[e]], layout.dim, layout.voxelSize,
                                      layout.regionVoxels(e), m.size[e], R0.data(), n);
    const Real kappa = elementVolumeStiffness(m.materials[m.elementMaterial[e]], layout.dim, layout.voxelSize,
                                              layout.regionVoxels(e), m.size[e], R0.data(), n);
    if (kappa > 0 && m.volumeStiffness.empty()) m.volumeStiffness.assign(E, 0);
    if (kappa > 0) m.volumeStiffness[e] = kappa;
    // The lightest vertex bounds the element's period from below.
    smallest = std::min(smallest, springPeriod(minMass, m.elementStiffnessBound(e)));
  }
  m.smallestPeriod = smallest;
}

// Step 4: the stiffness gathered at each vertex bounds its highest frequency (Gershgorin-like).
void vertexPeriod(RestModel& m) {
  std::vector<Real> kSum(m.numVertices(), 0.0);
  for (size_t e = 0; e < m.numElements(); ++e)
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) kSum[m.elemVerts[p]] += m.elementStiffnessBound(e);
  Real tv = std::numeric_limits<Real>::infinity();
  for (size_t i = 0; i < m.numVertices(); ++i) tv = std::min(tv, springPeriod(m.mass[i], kSum[i]));
  m.smallestVertexPeriod = tv;
}

// Step 5: surface vertices, the corners of the voxel faces on the body's boundary. Row by row:
// a voxel is looked at only when it is filled and one of its face neighbours is not (a byte test
// over the row and its four neighbour rows, which the compiler vectorises); the corners of its
// boundary faces are marked in a bitmap over the lattice, and each vertex then reads its point.
void markSurfaceVertices(const Layout& layout, const VoxelVolume& volume, RestModel& m) {
  const int D = m.dim;
  m.onSurface.assign(m.numVertices(), 0);
  const auto& n = volume.dims();
  const uint8_t* filled = volume.data().data();
  const size_t sx = size_t(n[0]) + 1, sy = size_t(n[1]) + 1;
  auto key = [&](const Int3& p) { return (size_t(p.z()) * sy + size_t(p.y())) * sx + size_t(p.x()); };
  std::vector<uint64_t> corner((sx * sy * (D == 3 ? size_t(n[2]) + 1 : 1) + 63) / 64, 0);
  const std::vector<uint8_t> none(size_t(n[0]), 0), all(size_t(n[0]), 1);
  std::vector<uint8_t> boundary(static_cast<size_t>(n[0]));
  const size_t stride[3] = {1, size_t(n[0]), size_t(n[0]) * size_t(n[1])};
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j) {
      const uint8_t* row = filled + volume.index(0, j, k);
      const uint8_t* ym = j > 0 ? row - stride[1] : none.data();
      const uint8_t* yp = j + 1 < n[1] ? row + stride[1] : none.data();
      const uint8_t* zm = D == 2 ? all.data() : k > 0 ? row - stride[2] : none.data();
      const uint8_t* zp = D == 2 ? all.data() : k + 1 < n[2] ? row + stride[2] : none.data();
      const int nx = n[0];
      for (int i = 0; i < nx; ++i) {
        const bool inner = i > 0 && i + 1 < nx && row[i - 1] && row[i + 1];
        boundary[size_t(i)] = (row[i] != 0) & !(inner & (ym[i] != 0) & (yp[i] != 0) & (zm[i] != 0) & (zp[i] != 0));
      }
      for (int i = 0; i < nx; ++i) {
        if (!boundary[size_t(i)]) continue;
        const size_t at = volume.index(i, j, k);
        const int c[3] = {i, j, k};
        for (int a = 0; a < D; ++a)
          for (int s = -1; s <= 1; s += 2) {
            // A filled face neighbour: no boundary face there (outside the grid counts as empty).
            const int q = c[a] + s;
            if (q >= 0 && q < n[a] && filled[s > 0 ? at + stride[a] : at - stride[a]]) continue;
            // The face of voxel (i,j,k) towards the neighbour: its corners.
            const int b0 = (a + 1) % 3, b1 = (a + 2) % 3;
            for (int u = 0; u < 2; ++u)
              for (int w = 0; w < (D == 3 ? 2 : 1); ++w) {
                Int3 p(i, j, k);
                p[a] += s > 0 ? 1 : 0;
                if (D == 3)
                  p[b0] += u, p[b1] += w;
                else
                  p[a == 0 ? 1 : 0] += u;
                const size_t b = key(p);
                corner[b >> 6] |= uint64_t(1) << (b & 63);
              }
          }
      }
    }
  for (size_t v = 0; v < m.numVertices(); ++v) {
    const size_t b = key(layout.vertices[v]);
    m.onSurface[v] = (corner[b >> 6] >> (b & 63)) & 1;
  }
}

}  // namespace

RestModel buildRestModel(const Layout& layout, const VoxelVolume& volume, const MaterialSettings& material,
                         const Vec3& origin) {
  validate(material);
  RestModel m;
  m.dim = layout.dim;
  m.voxelSize = layout.voxelSize;
  m.material = material;
  m.origin = projectToPlane(origin, m.dim);  // a 2D body lies in the plane z = 0 (plane.h)
  if (!m.origin.allFinite()) throw InputError("origin: must be finite");
  placeVertices(layout, m.origin, m);
  assignMaterials(layout, m);
  lumpMasses(layout, m);
  buildElements(layout, m);
  vertexPeriod(m);
  markSurfaceVertices(layout, volume, m);
  m.bodies.assign(1, wholeModelBody(m));
  return m;
}

BodyRange wholeModelBody(const RestModel& m) {
  BodyRange b;
  b.vertexEnd = uint32_t(m.numVertices()), b.elementEnd = uint32_t(m.numElements());
  b.voxelSize = m.voxelSize, b.origin = m.origin, b.material = m.material, b.dim = m.dim;
  return b;
}

size_t RestModel::bodyOfVertex(size_t v) const {
  const auto it =
      std::upper_bound(bodies.begin(), bodies.end(), v, [](size_t x, const BodyRange& b) { return x < b.vertexEnd; });
  if (it == bodies.end()) throw std::out_of_range("RestModel::bodyOfVertex: no body holds vertex " + std::to_string(v));
  return size_t(it - bodies.begin());
}

size_t RestModel::memoryBytes() const {
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  return sizeof(*this) + bytes(restPositions) + bytes(mass) + bytes(invMass) + bytes(onSurface) + bytes(stiffness) +
         bytes(size) + bytes(level) + bytes(elementMaterial) + bytes(elemStart) + bytes(elemVerts) +
         bytes(restCentroids) + bytes(bodies) + bytes(materials) + bytes(materialLabel) + bytes(dampingOwn) +
         bytes(dampingDefaultShare) + bytes(volumeStiffness);
}

const Vec3* RestModel::restOffsets(size_t e, std::vector<Vec3>& out) const {
  const uint32_t b = elemStart[e], n = elemStart[e + 1] - b;
  out.resize(n);
  for (uint32_t i = 0; i < n; ++i) out[i] = restOffset(e, b + i);
  return out.data();
}

std::vector<Vec3> RestModel::pairRestOffsets() const {
  std::vector<Vec3> R0(numPairs());
  for (size_t e = 0; e < numElements(); ++e)
    for (uint32_t p = elemStart[e]; p < elemStart[e + 1]; ++p) R0[p] = restOffset(e, p);
  return R0;
}

Real RestModel::elementStiffnessBound(size_t e) const {
  if (volumeStiffness.empty() || volumeStiffness[e] == 0) return stiffness[e];
  const uint32_t n = elemStart[e + 1] - elemStart[e];
  std::vector<Vec3> buffer;
  const Vec3* R0 = restOffsets(e, buffer);
  Mat3 V;  // the volumetric Hessian kappa g g^T's eigenvalue kappa sum |g_i|^2, g_i = V R0_i (element.h)
  if (volumeStrainMatrix(dim, R0, int(n), V)) {
    Real sum = 0;
    for (uint32_t i = 0; i < n; ++i) sum += (V * R0[i]).squaredNorm();
    return stiffness[e] + volumeStiffness[e] * sum;
  }
  const Real D = dim == 2 ? 2 : 3;  // isotropic: g_i = (D / tr S) R0_i, sum |g_i|^2 = D^2 / tr S
  return stiffness[e] + volumeStiffness[e] * D * D / restMomentTrace(R0, int(n));
}

}  // namespace gradel
