// Physical validation experiments (issue 5): a bar of square section along x, clamped at x = 0
// (a pin on that face), and the measurements `gradel-validate` reports and the tests check:
// the effective Young's modulus from a uniaxial stretch, the static tip sag under gravity, the
// first bending frequency from free vibration, against Euler-Bernoulli beam theory.
// The bar is built as a Scene and goes through buildScene like every other body.
#pragma once

#include <array>
#include <vector>

#include "gradel/scene.h"
#include "gradel/surface.h"

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

// ---- Poisson's ratio (issue 29) ---------------------------------------------------------------
// Uniaxial stress states and a squeezed ball, each set up as a plain world (no scene file): the
// material's poisson_ratio is what they measure. Lengths in m, strains signed (compression < 0).

/// What a uniaxial experiment measures once settled.
struct UniaxialResult {
  Real axial = 0;    ///< [-] axial strain (x).
  Real lateral = 0;  ///< [-] lateral strain, mean of y and z.
  Real volume = 1;   ///< [-] volume enclosed by the deformed voxel surface / the rest volume.
  Real modulus = 0;  ///< [Pa] 2 U / (V eps^2), U the elastic energy: Young's modulus of a uniaxial stress state.
  size_t vertices = 0, elements = 0;
};

/// A box of n^3 voxels (edge h) of material `m` pressed along x by `strain` (> 0) between two
/// frictionless walls whose gap is (1 - strain) of its length, free in y and z, settled with
/// damping 60/s over `steps` steps (dt of `integrator`: the stability rule for the explicit step,
/// 1/60 s for the frame-size ones). Strains from the body's extents (the state is homogeneous).
UniaxialResult compressBetweenWalls(const MaterialSettings& m, LayoutKind layout, int n, Real strain,
                                    IntegratorKind integrator = IntegratorKind::SymplecticEuler, int steps = 6000,
                                    Real h = 0.01);

/// A bar of `across` voxels square section and 4 x `across` along x (section 2 cm) held by two
/// frictionless grips: the end faces' vertices keep x = 0 and x = (1 + strain) L, free in y and
/// z, starting from the stretch alone; no gravity, damping 100/s, explicit steps for `duration` s. Lateral strain from the
/// vertices of the mid-length section, volume from the voxel surface, modulus from the energy.
UniaxialResult stretchBetweenGrips(const MaterialSettings& m, LayoutKind layout, int across, Real strain,
                                   Real duration = 0.3);

/// A ball of `size` voxels (5 mm each) squeezed between two sphere manipulators of twice its
/// radius, frictionless and inelastic, moving in along x until each has pressed `squeeze` of
/// the ball's radius in (0.15 s), then held (another 0.35 s; no gravity, damping 30/s).
struct BallSqueeze {
  Real volume = 1;   ///< [-] enclosed / rest volume at the end.
  Real widthY = 0;   ///< [-] the ball's extent across (y) at the end / at rest: the bulge.
  Real toolRadius = 0, toolX = 0;  ///< [m] the manipulators' radius and |x| of their centres from the ball's.
  Real ballRadius = 0;             ///< [m]
  /// The mid-plane (z = centre) sections of the voxel surface at rest and at the end, as
  /// segments (x0, y0, x1, y1) relative to the ball's centre [m].
  std::vector<std::array<Real, 4>> restSection, endSection;
};
BallSqueeze squeezeBall(const MaterialSettings& m, int size, Real squeeze);

/// Volume [m^3] enclosed by a closed display surface at the given model positions.
Real enclosedVolume(const DisplaySurface& surface, const std::vector<Vec3>& positions);

}  // namespace gradel
