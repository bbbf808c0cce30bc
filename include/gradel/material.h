// Material parameters and the two stiffness / mass scalings (paper sec. 2.2-2.3, DIGEST "open").
//
// `consistent` (default): masses lumped from cell volume and density (each filled cell gives
//   rho * volume / corners to each of its corners); element stiffness from a Young's-modulus-like
//   E [Pa] (Poisson ratio 0 model, mu = E / 2): k_e = E * V_e / lambda_max(S_e), with
//   S_e = sum_i R0_i R0_i^T (the rest offsets' second-moment matrix), lambda_max its largest
//   eigenvalue and V_e the element's region volume (area times voxelSize thickness in 2D).
//   Under a uniform strain eps (no rotation) the element stores k_e/2 tr(eps S_e eps^T), the
//   continuum E/2 |eps|^2 V_e. A complete element (a cube, or a square in 2D) has S_e = s I, so
//   k_e = D E V_e / tr S_e = E s_e / 2 for a cube of edge s_e: exact for every strain, a coarse
//   element as stiff as the fine elements it replaces. An incomplete element (fig. 6) whose
//   filled cells form a line (2x1x1 cells) or a plate (2x2x1) has an anisotropic S_e; one scalar
//   k_e cannot be exact in every direction, and this choice makes it exact along the region's
//   long axis (or plane) and softer across it (the line: 3/8 of E across; the plate: 3/8 normal
//   to it): never stiffer than the continuum in any direction. The former rule, D E V_e / tr S_e
//   (exact on average over directions), made a gradational bar 1.20 E stiff along its axis at
//   16 voxels across, because its incomplete elements all lie along the bar
//   (docs/validation/README.md).
//   Poisson's ratio nu (`poisson_ratio`, default 0): the shape-matching energy above is linear
//   isotropic elasticity with mu = E/2, lambda = 0 at small strain (k_e/2 tr(eps S eps^T) =
//   E/2 |eps|^2 V_e for a complete element). For nu > 0 k_e is divided by (1 + nu), so that
//   mu = E / (2 (1 + nu)), and each element gets a corotated volumetric energy kappa_e/2 e_v^2 on
//   its volumetric strain e_v about its best-fit rotation (element.h elementVolumeForces), kappa_e = lambda V_e,
//   lambda = E nu / ((1 + nu)(1 - 2 nu)): small-strain energy mu |eps|^2 + lambda/2 tr(eps)^2,
//   Young's modulus E and Poisson's ratio nu. 2D bodies are in plane strain (as the stress
//   output, element_strain.h): the same lambda, a lateral / axial strain nu / (1 - nu). `paper`
//   scaling uses the element's equivalent modulus k_e lambda_max(S_e) / V_e in place of E.
//   nu = 0 is exactly the model above (no volumetric term, no work).
// `paper`: every vertex has the mass of one voxel (rho h^3), and the displacement is divided by
//   the element's size (its block edge s_e in metres), f_i = k (M R0_i - r_i) / s_e, i.e.
//   k_e = k / s_e with k in newtons. Coarse elements are softer per metre; kept to reproduce
//   Table 1.
//
// Regions (docs/layout.md, docs/scenes.md `material.regions`): a labelled volume (volume.h) gives
//   each element one label (layout.h: no element mixes two), and each label its own Young's
//   modulus, density, paper k and (optionally) velocity damping rate. The scaling is the body's. Label 1 without an
//   entry of its own takes the body's fields, so a binary volume (every voxel label 1) is the one-material body.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "gradel/types.h"

namespace gradel {

enum class Scaling { Consistent, Paper };
Scaling parseScaling(const std::string& name);  ///< "consistent" | "paper"; InputError otherwise.
const char* scalingName(Scaling s);

/// The material of the voxels of one label (a region of a labelled volume).
struct RegionMaterial {
  uint16_t label = 2;          ///< Region label, 1..65535 (volume.h).
  Real youngsModulus = 1.0e5;  ///< [Pa] as MaterialSettings::youngsModulus.
  Real density = 1000.0;       ///< [kg/m^3] as MaterialSettings::density.
  Real paperK = 10000.0;       ///< [N] as MaterialSettings::paperK.
  Real poissonRatio = 0;       ///< as MaterialSettings::poissonRatio.
  /// [1/s] velocity damping rate of the region's vertices (v <- v / (1 + c dt), integrator.h);
  /// unset: the simulation's `damping`. A vertex on a border takes its regions' mass-weighted
  /// mean (model.h RestModel::vertexDamping).
  std::optional<Real> damping;
};

struct MaterialSettings {
  Scaling scaling = Scaling::Consistent;  ///< See above.
  Real youngsModulus = 1.0e5;             ///< [Pa] consistent scaling: Young's-modulus-like E (soft rubber / gel).
  Real density = 1000.0;                  ///< [kg/m^3] both scalings (paper: mass per voxel = density * h^3).
  Real paperK = 10000.0;                  ///< [N] paper scaling: force per unit strain (the paper's k).
  Real poissonRatio = 0;                  ///< Poisson's ratio nu in [0, 0.5) (see above); 0: no volumetric term.
  std::optional<Real> damping;            ///< [1/s] set only by a region's entry (regionMaterial);
                                          ///< unset: the simulation's damping.
  std::vector<RegionMaterial> regions;    ///< Per-label materials, distinct labels; label 1 without
                                          ///< an entry takes the fields above.
};

/// The material of the voxels of `label`: its entry of `m.regions` (with m's scaling), else for
/// label 1 the fields of m; `regions` of the result is empty. InputError
/// "regions: label L has no entry (...)" for another label without an entry.
MaterialSettings regionMaterial(const MaterialSettings& m, uint16_t label);

// ---- the rules, as pure functions (src/material.cpp); buildRestModel applies them (model.h) ----

/// `paper`: the mass of every vertex, one voxel's: density * h^3 [kg] (sec. 2.3).
Real paperVertexMass(const MaterialSettings& m, Real voxelSize);
/// `consistent`: the mass [kg] a filled cube of `cellEdge` voxels (a square slab one voxel thick
/// in 2D) gives each of its 2^dim corners: density * h^3 * cellEdge^dim / 2^dim.
Real cellCornerMass(const MaterialSettings& m, Real voxelSize, int cellEdge, int dim);
/// The second moment S = sum_i R0_i R0_i^T of an element's n rest offsets [m^2].
Mat3 restSecondMoment(const Vec3* restOffsets, size_t n);
/// An element's stiffness k_e [N/m]. `consistent`: E V_e / lambda_max(S) with S its rest offsets'
/// second moment (the top-left 2x2 block in 2D) and V_e = regionVoxels * h^3; `paper`: k / s_e
/// with s_e = elementSize [m]; either divided by (1 + nu) when m.poissonRatio nu > 0.
Real elementStiffness(const MaterialSettings& m, int dim, Real voxelSize, int64_t regionVoxels, Real elementSize,
                      const Vec3* restOffsets, size_t n);
/// The volumetric stiffness kappa_e = lambda V_e [J] of an element (see above; same arguments as
/// elementStiffness): 0 when m.poissonRatio is 0.
Real elementVolumeStiffness(const MaterialSettings& m, int dim, Real voxelSize, int64_t regionVoxels, Real elementSize,
                            const Vec3* restOffsets, size_t n);
/// The period [s] of a mass m [kg] on a spring k [N/m]: 2 pi sqrt(m / k). Every non-rigid mode of
/// a shape-matching element with vertex masses >= m has omega^2 <= k_e / m (sec. 3.4).
Real springPeriod(Real mass, Real stiffness);

}  // namespace gradel
