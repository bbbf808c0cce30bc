// Time-stepping settings (paper sec. 2.3, eqs. 2-3).
#pragma once

#include <algorithm>
#include <string>
#include <thread>

#include "gradel/types.h"

namespace gradel {

/// ForwardEuler: the paper's literal eqs. 2-3, P(T+dT) = P(T) + V(T) dT (gains energy on an
///   undamped oscillator; kept to reproduce the paper).
/// SymplecticEuler (default): V(T+dT) = V(T) + A(T) dT, then P(T+dT) = P(T) + V(T+dT) dT; its
///   energy stays bounded for any dt below the stability limit, which is why it is the default.
/// Implicit: projective dynamics (projective.h), backward Euler on the same element energy;
///   stable at any dt (dt = auto means 1/60 s here), dissipative.
/// LargeStep: implicit midpoint by Newton-PCG, backward Euler in steps near contacts (large_step.h);
///   stable at any dt (dt = auto means 1/60 s), keeps a mode's amplitude and a spin's momentum.
/// Auto: chosen when the World is built: whichever of symplectic (at its dt = auto) and large_step
///   (at the scene's dt, or 1/60 s) costs less wall time per simulated second by the measured
///   cost model below (integratorCost); World::integratorChoice() says which and why.
enum class IntegratorKind { SymplecticEuler, ForwardEuler, Implicit, LargeStep, Auto };
/// "symplectic" | "forward_euler" | "implicit" | "large_step" | "auto"
IntegratorKind parseIntegratorKind(const std::string& name);
const char* integratorKindName(IntegratorKind k);

/// What "the smallest period" means for dt = auto.
/// Operator (default): 2 pi / omega_max, the fastest vibration of the assembled body at rest
///   (stability.h: Lanczos on M^-1 K, hanging vertices and regions included). Symplectic Euler is
///   stable while omega_max dt < 2, i.e. dt_fraction < 1/pi = 0.318 of a linear body at rest; the
///   default 0.175 keeps omega_max dt = 1.10, ~1.8x the vertex rule's steps on the shipped scenes.
///   0.175 by measurement (docs/scenes.md, dt_fraction): a body squeezed between obstacles and
///   walls stiffens above its rest operator, and the contact-energy property's worst case found
///   pumps energy from 0.2 (holds to 0.19); 100 property cases hold at 0.175.
/// Vertex: the period of the stiffest vertex with all its elements (a bound 0-15 % above the
///   operator's omega_max); dt = T/10 keeps omega dt ~ 0.6 for every mode (the default before
///   issue 25).
/// Element: the paper's rule (sec. 3.4), the period of the smallest element on its own. A vertex
///   shared by n elements vibrates ~sqrt(n) times faster, so dt = T/10 lands at omega dt ~ 1.8,
///   just inside symplectic Euler's stability limit of 2: stable but with large energy swings
///   (scenes/paper-table1.json asks for it).
enum class PeriodRule { Operator, Vertex, Element };
PeriodRule parsePeriodRule(const std::string& name);  ///< "operator" | "vertex" | "element"
const char* periodRuleName(PeriodRule r);
/// dt_fraction when none is given (SimulationSettings::dtFraction = 0): operator 0.175, vertex and element the
/// paper's 0.1.
Real defaultDtFraction(PeriodRule r);
/// The largest dt_fraction accepted with a rule: where symplectic Euler is still stable with a
/// margin (operator 0.3, against the limit 1/pi; vertex 0.3, measured to diverge from 0.33 on the
/// shipped scenes; element 0.1, measured to diverge from 0.15 on paper-table1).
Real maxDtFraction(PeriodRule r);

/// One worker thread per hardware thread (at least 1, at most 1024): the default, since results
/// are identical at any count and the step's thread team never waits by spinning for long.
inline int hardwareThreads() { return int(std::clamp(std::thread::hardware_concurrency(), 1u, 1024u)); }

/// Wall time of one vertex-step [s], rounded up: explicit (measured 11-30 ns, docs/speed.md) and
/// implicit (~4 us on the 12^3 strike scene, projective.h) integrators. Used by `auto` to pick an
/// integrator and by the run budget to estimate a run's time.
inline constexpr double kExplicitSecondsPerVertexStep = 30e-9;
inline constexpr double kImplicitSecondsPerVertexStep = 4e-6;
/// The cost model of `auto`: wall seconds per vertex and step of each integrator on 2 threads of
/// the project's 2-core VM with other work on it, on the real-scene rows of gradel-bench (a sphere
/// on the floor under gravity, pressed by a manipulator, pinned, frames every 1/60 s;
/// bench/results/2026-11-27-vm-auto.csv, docs/speed.md "Which integrator auto picks"). The
/// explicit step's cost per vertex is flat in the body's size (25-40 ns); the large step's grows
/// as vertices^0.55 (its factor solves: 10-13 us at 1,667 vertices, 17-21 us at 7,037, 49-61 us at
/// 31,007). Only their ratio decides the pick.
inline constexpr double kAutoExplicitSecondsPerVertexStep = 30e-9;   ///< [s] symplectic, contacts included.
inline constexpr double kAutoLargeStepSecondsPerVertexStep = 11e-6;  ///< [s] large step at kAutoLargeStepVertices.
inline constexpr double kAutoLargeStepVertices = 1667;               ///< the 16-voxel sphere's vertices.
inline constexpr double kAutoLargeStepExponent = 0.55;               ///< growth of its cost per vertex-step.

/// What `auto` compares: wall seconds per simulated second of each integrator for a body of
/// `vertices` vertices, the explicit step at `explicitDt` and the large step at `largeDt`.
struct IntegratorCost {
  IntegratorKind pick = IntegratorKind::SymplecticEuler;  ///< The cheaper one (symplectic on a tie).
  double explicitWallPerSecond = 0;   ///< [s / s] symplectic.
  double largeStepWallPerSecond = 0;  ///< [s / s] large step.
};
IntegratorCost integratorCost(size_t vertices, double explicitDt, double largeDt);

struct SimulationSettings {
  IntegratorKind integrator = IntegratorKind::SymplecticEuler;
  Real dt = 0;  ///< [s] time step; 0 = auto: dtFraction of the smallest period (dtPeriod).
  Real dtFraction = 0;  ///< [-] used when dt is auto, up to maxDtFraction(dtPeriod); 0 = defaultDtFraction(dtPeriod).
  PeriodRule dtPeriod = PeriodRule::Operator;  ///< Which smallest period dt = auto refers to (docs/scenes.md).
  Real damping = 0.0;         ///< [1/s] velocity damping rate c: v <- v / (1 + c dt) every step (never adds energy).
  Vec3 gravity{0, -9.81, 0};  ///< [m/s^2]
  int threads = hardwareThreads();  ///< Worker threads (results are identical at any count).
  int rotationIterations = 4;       ///< Max warm-started rotation refinements per element per step.
  int implicitIterations = 10;      ///< Implicit only: local/global passes per step (projective.h).
  int largeStepPasses = 10;         ///< LargeStep only: conjugate-gradient iterations per substep (large_step.h).
  int largeStepSubsteps =
      2;  ///< LargeStep only: midpoint substeps per step (2: the bar's 13 Hz mode within 4 % at 1/60 s).
  int largeStepCoarseNodes = 27;  ///< LargeStep only: most coarse-grid nodes per body of the two-level
                                  ///< preconditioner (coarse_space.h; 0 = the projective factor alone).
};

}  // namespace gradel
