// Material parameters and the two stiffness / mass scalings (paper sec. 2.2-2.3, DIGEST "open").
//
// `consistent` (default): masses lumped from cell volume and density (each filled cell gives
//   rho * volume / corners to each of its corners); element stiffness from a Young's-modulus-like
//   E [Pa] so that a uniform strain stores the same energy density in every element, whatever
//   its size: k_e = 2 * D * mu * V_e / sum_i |R0_i|^2 with mu = E / 2 (Poisson ratio 0 model),
//   V_e the element's region volume (area times voxelSize thickness in 2D). For a cube element of
//   edge s this is k_e = E s / 2: coarse elements are stiffer per metre of displacement, exactly
//   as stiff as the 8 fine elements they replace.
//
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
  Real youngsModulus = 1.0e5;            ///< [Pa] consistent scaling: Young's-modulus-like E (soft rubber / gel).
  Real density = 1000.0;                 ///< [kg/m^3] both scalings (paper: mass per voxel = density * h^3).
  Real paperK = 10000.0;                 ///< [N] paper scaling: force per unit strain (the paper's k).
};

}  // namespace gradel
