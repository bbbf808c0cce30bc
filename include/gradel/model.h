// The rest model: everything about a body that is computed once from its layout and material
// and only read afterwards (Jolt's "shared settings"). Hot per-pair data is contiguous, in the
// layout's compressed-row order.
#pragma once

#include <vector>

#include "gradel/layout.h"
#include "gradel/material.h"

namespace gradel {

/// One body's share of a model (a World steps several bodies as one combined model,
/// bodies.h): its vertices [vertexBegin, vertexEnd) and elements [elementBegin, elementEnd)
/// (whose pairs are elemStart[elementBegin] .. elemStart[elementEnd]), and the body's lattice
/// and material.
struct BodyRange {
  uint32_t vertexBegin = 0, vertexEnd = 0;
  uint32_t elementBegin = 0, elementEnd = 0;
  Real voxelSize = 1;    ///< [m] the body's voxel edge.
  Vec3 origin{0, 0, 0};  ///< [m] world position of the body's lattice point (0, 0, 0) at rest.
  MaterialSettings material;
  int dim = 3;
  uint32_t numVertices() const { return vertexEnd - vertexBegin; }
  uint32_t numElements() const { return elementEnd - elementBegin; }
};

struct RestModel {
  int dim = 3;
  // Body 0's lattice and material (for a one-body model, the body's); per body: `bodies`.
  Real voxelSize = 1;         ///< [m] body 0's voxel edge.
  MaterialSettings material;  ///< Body 0's material as given (with its per-label `regions`).
  Vec3 origin{0, 0, 0};       ///< [m] world position of body 0's lattice point (0, 0, 0) at rest.
  /// The bodies, in vertex and element order (buildRestModel: one, covering everything;
  /// combineRestModels: one per combined model). Never empty for a built model.
  std::vector<BodyRange> bodies;

  // ---- per vertex ----
  std::vector<Vec3> restPositions;  ///< [m] origin + lattice * voxelSize (buildRestModel).
  std::vector<Real> mass;           ///< [kg] lumped (consistent) or one voxel's mass (paper).
  std::vector<Real> invMass;        ///< [1/kg]
  std::vector<uint8_t> onSurface;   ///< 1 if the vertex is a corner of a voxel face on the body's boundary.

  // ---- per element ----
  std::vector<Real> stiffness;            ///< k_e [N/m], see material.h.
  std::vector<Real> size;                 ///< [m] block edge 2 * cellSize * h (voxel layout: h); normalises stress.
  std::vector<uint8_t> level;             ///< Layout level (0 = finest).
  std::vector<uint16_t> elementMaterial;  ///< Index into `materials` of the element's region.
  /// kappa_e = lambda V_e [J], the volumetric term's stiffness (material.h, element.h
  /// elementVolumeForces); empty when every material's poisson_ratio is 0 (no volumetric work).
  std::vector<Real> volumeStiffness;

  // ---- materials per region (material.h regionMaterial): one per label of the layout ----
  std::vector<MaterialSettings> materials;  ///< Ascending label; the stiffness and masses above come from them.
  std::vector<uint16_t> materialLabel;      ///< The label of each entry of `materials` ({1} for a binary volume).

  // ---- damping per region (material.regions[i].damping); both empty when no region sets one ----
  // A vertex's rate is the mass-weighted mean over the regions whose cells give it mass (the
  // lumped form of mass-proportional damping, sum_r c_r m_ir v_i; `paper` scaling: weighted by
  // each owning element's voxel mass), a region without its own rate counting with the
  // simulation's: c_i = dampingOwn[i] + dampingDefaultShare[i] * c_simulation (vertexDamping).
  // A vertex inside one region gets that region's rate exactly.
  std::vector<Real> dampingOwn;           ///< [1/s] per vertex: sum of weight share x rate over regions with a rate.
  std::vector<Real> dampingDefaultShare;  ///< Per vertex: weight share of regions without a rate, in [0, 1].

  // ---- element -> vertex (compressed rows) ----
  std::vector<uint32_t> elemStart;  ///< Size elements + 1.
  std::vector<uint32_t> elemVerts;  ///< Vertex id per pair.

  // ---- per element: rest centroids ----
  /// C_e [m] per element: the mean of its vertices' rest positions (summed in pair order, then
  /// divided by the count). An element's rest offsets R0_i = X_i - C_e are formed from these
  /// on demand (restOffsets below), not kept per pair (24 bytes a pair, ~72 bytes a vertex on a
  /// gradational sphere; docs/speed.md, "Fourth pass").
  std::vector<Vec3> restCentroids;

  Real totalMass = 0;  ///< [kg]
  Real smallestPeriod =
      0;  ///< [s] the paper's "smallest element period": min over elements of 2 pi sqrt(m_min / k_e) (sec. 3.4).
  Real smallestVertexPeriod = 0;  ///< [s] min over vertices of 2 pi sqrt(m_i / sum_{e at i} k_e): a vertex shared by n
                                  ///< elements vibrates ~sqrt(n) times faster than one element.

  size_t numVertices() const { return restPositions.size(); }
  size_t numElements() const { return stiffness.size(); }
  /// Bytes held by all arrays of the model (capacity, not size).
  size_t memoryBytes() const;
  size_t numPairs() const { return elemVerts.size(); }
  size_t numBodies() const { return bodies.size(); }
  /// Pair p's rest offset R0 [m]: its vertex's rest position minus element e's rest centroid
  /// (p one of e's pairs).
  Vec3 restOffset(size_t e, size_t p) const { return restPositions[elemVerts[p]] - restCentroids[e]; }
  /// Element e's rest offsets R0_i [m] in its pair order, written into `out` (resized to its
  /// vertex count; the caller keeps it across elements to reuse its storage): what element.h's
  /// kernels and material.h take. Returns out.data().
  const Vec3* restOffsets(size_t e, std::vector<Vec3>& out) const;
  /// Every pair's rest offset [m], in pair order: for solvers that read them in every product
  /// (the large step, the estimate's reference operator) and keep their own copy while they live.
  std::vector<Vec3> pairRestOffsets() const;
  /// True if some element has a volumetric term (volumeStiffness is filled).
  bool hasVolumeTerm() const { return !volumeStiffness.empty(); }
  /// Element e's stiffness bound [N/m]: its rest Hessian is <= this times the identity on its
  /// vertices: k_e, plus kappa_e D^2 / tr S_e with a volumetric term (its Hessian along its force
  /// is kappa_e g g^T, g_i = (D / tr S_e) M R0_i, |g|^2 = D^2 / tr S_e; element.h).
  Real elementStiffnessBound(size_t e) const;
  /// True if some region sets its own damping rate (dampingOwn is filled).
  bool hasRegionDamping() const { return !dampingOwn.empty(); }
  /// Vertex v's velocity damping rate [1/s] given the simulation's rate (the regions' rates above;
  /// `simulationDamping` itself when no region sets one).
  Real vertexDamping(size_t v, Real simulationDamping) const {
    return dampingOwn.empty() ? simulationDamping : dampingOwn[v] + dampingDefaultShare[v] * simulationDamping;
  }
  /// The body that holds vertex v (bodies are contiguous and ascending; a binary search).
  size_t bodyOfVertex(size_t v) const;
};

/// One body covering every vertex and element of `m`, with m's lattice and material (what
/// buildRestModel puts into RestModel::bodies).
BodyRange wholeModelBody(const RestModel& m);

/// Builds the rest model. `origin` is the world position [m] of lattice point (0,0,0); a 2D
/// body lies in the plane z = 0 (origin's z is dropped). Each element takes the material of its
/// label (layout.label, material.h regionMaterial): its stiffness from that material's rules and
/// its cells' masses from that material's density. Throws InputError for invalid material
/// parameters (validate(MaterialSettings)), a label of the layout without a material
/// ("regions: label 3 ..."), or a non-finite origin.
RestModel buildRestModel(const Layout& layout, const VoxelVolume& volume, const MaterialSettings& material,
                         const Vec3& origin);

}  // namespace gradel
