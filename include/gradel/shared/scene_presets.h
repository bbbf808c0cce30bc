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

/// What a user runs (issue 10's "real scene"): SI units (`consistent` scaling, Young's modulus
/// `youngsModulus` [Pa], 1000 kg/m^3), a sphere of fixed physical diameter (0.32 m, so the voxel
/// is 0.32 / size m and finer grids mean smaller voxels, as in the viewer) resting on the floor
/// of a box domain (walls, restitution 0.3, friction 0.3), gravity, damping 1/s, dt = 1/10 of the
/// smallest vertex period (the default rule), a sphere manipulator (radius 0.06 m) pressing down
/// on the top of the body by 1.6 cm over the first 0.05 s and then holding, and a pin holding a
/// small patch of the body's side (x < 1.5 voxels from the left, the body's rest position).
/// The benchmark adds metrics and stress once per output frame (frameInterval, 1/60 s).
Scene realBenchScene(int size, Real youngsModulus, LayoutKind layout, int threads = 1);

/// Soft-soft contact (issue 12): two spheres of `size` voxels (0.01 m) meeting head on at 0.5 m/s
/// each, the scenes/two-balls.json setting (restitution 0.5, friction 0.2, no gravity, dt auto,
/// explicit): the measurement of the body-contact stage's share of a step.
Scene contactBenchScene(int size, int threads = 1);

}  // namespace gradel
