#include "gradel/model.h"

#include <array>
#include <cmath>
#include <numbers>
#include <unordered_map>

#include <Eigen/Eigenvalues>

namespace gradel {

Scaling parseScaling(const std::string& name) {
  if (name == "consistent") return Scaling::Consistent;
  if (name == "paper") return Scaling::Paper;
  throw InputError("unknown scaling '" + name + "' (expected consistent or paper)");
}

const char* scalingName(Scaling s) { return s == Scaling::Paper ? "paper" : "consistent"; }

namespace {

uint64_t packLattice(const Int3& p) {
  // 21 bits per axis: lattice coordinates are in [0, 2^21) (volumes up to 2 million voxels a side).
  return (uint64_t(uint32_t(p.x())) << 42) | (uint64_t(uint32_t(p.y())) << 21) | uint64_t(uint32_t(p.z()));
}

void checkPositive(Real v, const char* field) {
  if (!(v > 0) || !std::isfinite(v))
    throw InputError(std::string("material.") + field + " must be a positive finite number");
}

}  // namespace

RestModel buildRestModel(const Layout& layout, const VoxelVolume& volume, const MaterialSettings& material,
                         const Vec3& origin) {
  checkPositive(material.density, "density");
  if (material.scaling == Scaling::Consistent)
    checkPositive(material.youngsModulus, "youngs_modulus");
  else
    checkPositive(material.paperK, "k");
  if (!origin.allFinite()) throw InputError("body.position must be finite");

  RestModel m;
  m.dim = layout.dim;
  m.voxelSize = layout.voxelSize;
  m.material = material;
  const int D = layout.dim;
  const Real h = layout.voxelSize;
  const size_t V = layout.numVertices(), E = layout.numElements(), P = layout.numPairs();

  std::unordered_map<uint64_t, uint32_t> vertexAt;
  vertexAt.reserve(V * 2);
  m.restPositions.resize(V);
  for (size_t i = 0; i < V; ++i) {
    m.restPositions[i] = origin + layout.vertices[i].cast<Real>() * h;
    vertexAt.emplace(packLattice(layout.vertices[i]), uint32_t(i));
  }
  auto idOf = [&](const Int3& p) -> uint32_t {
    auto it = vertexAt.find(packLattice(p));
    return it == vertexAt.end() ? UINT32_MAX : it->second;
  };

  // ---- masses ----
  // Volume of one lattice voxel; 2D bodies are slabs one voxel thick.
  const Real voxelVolume = h * h * h;
  m.mass.assign(V, 0.0);
  if (material.scaling == Scaling::Paper) {
    m.mass.assign(V, material.density * voxelVolume);  // "reduced mass per voxel" (sec. 2.3)
  } else {
    // Each filled cell (the whole block for a full element) gives its mass in equal parts to
    // its corners; those are always model vertices (an element's own vertices).
    const int corners = D == 3 ? 8 : 4;
    for (size_t e = 0; e < E; ++e) {
      const bool full = layout.isFull(e);
      const int cs = full ? 2 * layout.cellSize[e] : layout.cellSize[e];
      const Real cellMass = material.density * voxelVolume * std::pow(Real(cs), D);
      const int cells = D == 3 ? 8 : 4;
      for (int c = 0; c < (full ? 1 : cells); ++c) {
        if (!full && !(layout.cellMask[e] >> c & 1)) continue;
        const Int3 lo =
            layout.origin[e] + (full ? Int3(0, 0, 0) : Int3(c & 1, (c >> 1) & 1, (c >> 2) & 1) * layout.cellSize[e]);
        for (int k = 0; k < corners; ++k) {
          const Int3 p = lo + Int3(k & 1, (k >> 1) & 1, D == 3 ? (k >> 2) & 1 : 0) * cs;
          const uint32_t id = idOf(p);
          if (id == UINT32_MAX) throw std::logic_error("buildRestModel: a cell corner is not a model vertex");
          m.mass[id] += cellMass / corners;
        }
      }
    }
  }
  m.invMass.resize(V);
  m.totalMass = 0;
  for (size_t i = 0; i < V; ++i) {
    if (!(m.mass[i] > 0)) throw std::logic_error("buildRestModel: a vertex has no mass");
    m.invMass[i] = 1.0 / m.mass[i];
    m.totalMass += m.mass[i];
  }

  // ---- elements ----
  m.elemStart = layout.elemStart;
  m.elemVerts = layout.elemVerts;
  m.level = layout.level;
  m.restOffsets.resize(P);
  m.stiffness.resize(E);
  m.size.resize(E);
  Real smallest = std::numeric_limits<Real>::infinity();
  for (size_t e = 0; e < E; ++e) {
    const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    Vec3 c = Vec3::Zero();
    for (uint32_t p = b; p < b + n; ++p) c += m.restPositions[m.elemVerts[p]];
    c /= Real(n);
    Real minMass = std::numeric_limits<Real>::infinity();
    for (uint32_t p = b; p < b + n; ++p) {
      m.restOffsets[p] = m.restPositions[m.elemVerts[p]] - c;
      minMass = std::min(minMass, m.mass[m.elemVerts[p]]);
    }
    m.size[e] = (layout.kind == LayoutKind::Voxel ? 1 : 2) * layout.cellSize[e] * h;
    if (material.scaling == Scaling::Paper) {
      m.stiffness[e] = material.paperK / m.size[e];  // displacement / element size (sec. 2.2)
    } else {
      // No direction stiffer than the continuum (material.h): k_e = E V_e / lambda_max(S),
      // S = sum R0_i R0_i^T. A complete element's S is isotropic and this is D E V_e / tr S.
      Mat3 S = Mat3::Zero();
      for (uint32_t p = b; p < b + n; ++p) S.noalias() += m.restOffsets[p] * m.restOffsets[p].transpose();
      const Real lambdaMax =
          D == 3 ? Eigen::SelfAdjointEigenSolver<Mat3>(S, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff()
                 : Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(S.topLeftCorner<2, 2>(), Eigen::EigenvaluesOnly)
                       .eigenvalues()
                       .maxCoeff();
      const Real regionVolume = Real(layout.regionVoxels(e)) * voxelVolume;
      m.stiffness[e] = material.youngsModulus * regionVolume / lambdaMax;
    }
    // Every non-rigid mode of a shape-matching element with masses m has omega^2 = k_e / m; the
    // lightest vertex bounds the period from below (sec. 3.4).
    smallest = std::min(smallest, 2 * std::numbers::pi * std::sqrt(minMass / m.stiffness[e]));
  }
  m.smallestPeriod = smallest;

  // Stiffness gathered at each vertex bounds its highest frequency (Gershgorin-like).
  {
    std::vector<Real> kSum(V, 0.0);
    for (size_t e = 0; e < E; ++e)
      for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) kSum[m.elemVerts[p]] += m.stiffness[e];
    Real tv = std::numeric_limits<Real>::infinity();
    for (size_t i = 0; i < V; ++i) tv = std::min(tv, 2 * std::numbers::pi * std::sqrt(m.mass[i] / kSum[i]));
    m.smallestVertexPeriod = tv;
  }

  // ---- surface vertices: corners of boundary faces ----
  m.onSurface.assign(V, 0);
  const auto& n = volume.dims();
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        if (!volume.isSurface(i, j, k)) continue;
        for (int a = 0; a < D; ++a)
          for (int s = -1; s <= 1; s += 2) {
            Int3 q(i, j, k);
            q[a] += s;
            if (volume.at(q.x(), q.y(), q.z())) continue;
            // The face of voxel (i,j,k) towards q: its corners.
            const int b0 = (a + 1) % 3, b1 = (a + 2) % 3;
            for (int u = 0; u < 2; ++u)
              for (int w = 0; w < (D == 3 ? 2 : 1); ++w) {
                Int3 p(i, j, k);
                p[a] += s > 0 ? 1 : 0;
                if (D == 3)
                  p[b0] += u, p[b1] += w;
                else
                  p[a == 0 ? 1 : 0] += u;
                const uint32_t id = idOf(p);
                if (id != UINT32_MAX) m.onSurface[id] = 1;
              }
          }
      }
  return m;
}

size_t RestModel::memoryBytes() const {
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  return sizeof(*this) + bytes(restPositions) + bytes(mass) + bytes(invMass) + bytes(onSurface) + bytes(stiffness) +
         bytes(size) + bytes(level) + bytes(elemStart) + bytes(elemVerts) + bytes(restOffsets);
}

}  // namespace gradel
