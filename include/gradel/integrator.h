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
/// Auto: chosen when the World is built: symplectic while its dt = auto keeps real time (estimated
///   from the vertex count and kAutoExplicitSecondsPerVertexStep below),
///   large_step when it cannot (World::integratorChoice() says which and why).
enum class IntegratorKind { SymplecticEuler, ForwardEuler, Implicit, LargeStep, Auto };
/// "symplectic" | "forward_euler" | "implicit" | "large_step" | "auto"
IntegratorKind parseIntegratorKind(const std::string& name);
const char* integratorKindName(IntegratorKind k);

/// What "the smallest period" means for dt = auto.
/// Element: the paper's rule (sec. 3.4), the period of the smallest element on its own. A vertex
///   shared by n elements vibrates ~sqrt(n) times faster, so dt = T/10 lands at omega dt ~ 1.8,
///   just inside symplectic Euler's stability limit of 2: stable but with large energy swings.
/// Vertex (default): the period of the stiffest vertex with all its elements; dt = T/10 then
///   keeps omega dt ~ 0.6 for every mode.
enum class PeriodRule { Vertex, Element };
PeriodRule parsePeriodRule(const std::string& name);  ///< "vertex" | "element"
const char* periodRuleName(PeriodRule r);

/// One worker thread per hardware thread (at least 1, at most 1024): the default, since results
/// are identical at any count and the step's thread team never waits by spinning for long.
inline int hardwareThreads() { return int(std::clamp(std::thread::hardware_concurrency(), 1u, 1024u)); }

/// Wall time of one vertex-step [s], rounded up: explicit (measured 11-30 ns, docs/speed.md) and
/// implicit (~4 us on the 12^3 strike scene, projective.h) integrators. Used by `auto` to pick an
/// integrator and by the run budget to estimate a run's time.
inline constexpr double kExplicitSecondsPerVertexStep = 30e-9;
inline constexpr double kImplicitSecondsPerVertexStep = 4e-6;
/// What `auto` assumes an explicit vertex-step costs [s] on one thread of a machine that is doing
/// other work too (measured on the real scenes of gradel-bench beside other builds: 85-150 ns per
/// vertex-step on the 2-core VM, docs/speed.md "Which integrator auto picks"; 11-30 ns when quiet).
/// `auto` counts no thread speed-up (under load the governor often runs one member): it keeps the
/// explicit step only where that runs in real time on a busy machine, since a wrong explicit pick
/// runs far below real time while a wrong large-step pick still runs at frame rate.
inline constexpr double kAutoExplicitSecondsPerVertexStep = 100e-9;

struct SimulationSettings {
  IntegratorKind integrator = IntegratorKind::SymplecticEuler;
  Real dt = 0;                               ///< [s] time step; 0 = auto: dtFraction of the smallest element's period.
  Real dtFraction = 0.1;                     ///< [-] the paper's 1/10 (sec. 3.4), used when dt is auto.
  PeriodRule dtPeriod = PeriodRule::Vertex;  ///< Which smallest period dt = auto refers to.
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
