// Scenes built in code (the JSON scenes live in scenes/): used by the benchmark and tests.
#pragma once

#include "gradel/scene.h"

namespace gradel {

/// The paper's Table 1 setting (sec. 3.4) for any preset shape and size: lattice units
/// (voxel_size 1 m, density 1 kg/m^3: one voxel's mass per vertex), `paper` scaling with
/// k = 10000 N, dt = 1/10 of the smallest element's period (dt_period element), symplectic Euler,
/// no gravity, no damping, no walls or manipulators. The body starts with a smooth 3 % stretch
/// and shear (applied by preparePaperBench), so every element has a real rotation fit to do.
Scene paperBenchScene(const std::string& shape, int size, LayoutKind layout, int threads = 1);

/// Applies the starting deformation of paperBenchScene to a freshly built world.
void preparePaperBench(World& world);

}  // namespace gradel
