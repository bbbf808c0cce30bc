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
enum class IntegratorKind { SymplecticEuler, ForwardEuler, Implicit };
IntegratorKind parseIntegratorKind(const std::string& name);  ///< "symplectic" | "forward_euler" | "implicit"
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
};

}  // namespace gradel
