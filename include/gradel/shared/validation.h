// Physical validation experiments (issue 5): a bar of square section along x, clamped at x = 0
// (a pin on that face), and the measurements `gradel-validate` reports and the tests check:
// the effective Young's modulus from a uniaxial stretch, the static tip sag under gravity, the
// first bending frequency from free vibration, against Euler-Bernoulli beam theory.
// The bar is built as a Scene and goes through buildScene like every other body.
#pragma once

#include <vector>

#include "gradel/scene.h"

namespace gradel {

/// Two materials in one bar (materials per region): `Series` makes the far half (x >= L/2)
/// label 2, `Parallel` the upper half of the section (y >= a/2); the rest is label 1. The
/// materials are BarSpec::material (label 1) and its `regions` entry for label 2.
enum class BarSplit { None, Series, Parallel };

struct BarSpec {
  int across = 2;     ///< Voxels across the square section (y and z).
  int along = 16;     ///< Voxels along the bar (x).
  Real width = 0.02;  ///< [m] edge of the section a; voxel size = width / across.
  LayoutKind layout = LayoutKind::Uniform;
  MaterialSettings material;
  BarSplit split = BarSplit::None;
  Real voxelSize() const { return width / across; }
  Real length() const { return along * voxelSize(); }  ///< [m] L.
};

/// A pin holding the bar's face x = x0 (every vertex in a slab half a voxel thick around it).
PinSettings barFacePin(const BarSpec& bar, Real x0);

/// The bar at rest from (0, 0, 0) to (L, a, a), no walls, gravity -9.81 y, clamped at x = 0
/// (every vertex on that face pinned) unless `clamped` is false.
Scene barScene(const BarSpec& bar, const SimulationSettings& sim, bool clamped = true);

/// Euler-Bernoulli cantilever of length L, square section a, density rho, modulus E, gravity g:
/// tip sag rho g A L^4 / (8 E I) with I = a^4 / 12 [m]; first bending frequency
/// 1.875^2 / (2 pi L^2) sqrt(E I / (rho A)) [Hz].
Real beamTipSag(Real L, Real a, Real rho, Real E, Real g = 9.81);
Real beamFrequency(Real L, Real a, Real rho, Real E);

/// The stretch modulus [Pa] of a bar of two equal halves of moduli E1 and E2: in series
/// (Reuss) 2 / (1/E1 + 1/E2), in parallel (Voigt) (E1 + E2) / 2; E1 for BarSplit::None. Exact for
/// a Poisson-ratio-0 material such as the element model's.
Real mixtureModulus(BarSplit split, Real E1, Real E2);

/// Effective Young's modulus [Pa] of the bar's element model: both end faces pinned, the far one
/// moved by `strain` L along x, static equilibrium (projective.h solveStatic), E = F L / (A dL)
/// with F the elastic force on the moved face.
Real stretchModulus(const BarSpec& bar, Real strain = 1e-3);

struct SagResult {
  Real sag = 0;      ///< [m] mean downward displacement of the free end face's vertices.
  size_t steps = 0;  ///< Explicit steps of the dynamic relaxation.
  size_t elements = 0, vertices = 0;
};
/// Static tip sag of the clamped bar under gravity. Projective dynamics' local/global iteration
/// converges very slowly on bending (each pass holds the element rotations fixed), so this is a
/// dynamic relaxation: undamped symplectic steps with kinetic damping (every velocity set to zero
/// whenever the kinetic energy passes a peak), until the sag changes by less than `tolerance`
/// (relative) between resets, or `maxSteps`.
SagResult staticTipSag(const BarSpec& bar, size_t maxSteps = 2000000, Real tolerance = 1e-6);

/// Frequency [Hz] of the strongest peak of a uniformly sampled signal (mean removed, Hann
/// window), refined on a fine grid of the discrete-time Fourier transform.
Real dominantFrequency(const std::vector<Real>& signal, Real sampleInterval);

/// Ids of the vertices on the bar's free end face (x = L at rest).
std::vector<uint32_t> tipVertices(const RestModel& model, Real length);

}  // namespace gradel
