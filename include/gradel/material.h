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
// `paper`: every vertex has the mass of one voxel (rho h^3), and the displacement is divided by
//   the element's size (its block edge s_e in metres), f_i = k (M R0_i - r_i) / s_e, i.e.
//   k_e = k / s_e with k in newtons. Coarse elements are softer per metre; kept to reproduce
//   Table 1.
#pragma once

#include <string>

#include "gradel/types.h"

namespace gradel {

enum class Scaling { Consistent, Paper };
Scaling parseScaling(const std::string& name);  ///< "consistent" | "paper"; InputError otherwise.
const char* scalingName(Scaling s);

struct MaterialSettings {
  Scaling scaling = Scaling::Consistent;  ///< See above.
  Real youngsModulus = 1.0e5;             ///< [Pa] consistent scaling: Young's-modulus-like E (soft rubber / gel).
  Real density = 1000.0;                  ///< [kg/m^3] both scalings (paper: mass per voxel = density * h^3).
  Real paperK = 10000.0;                  ///< [N] paper scaling: force per unit strain (the paper's k).
};

}  // namespace gradel
