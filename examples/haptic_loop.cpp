// A haptic loop at 1 kHz: a manipulator (the tool's proxy) coupled to a device position by a
// virtual spring-damper, the body's contact force on the proxy fed back (World::averageContactForces).
// A scripted device path stands in for the device: it moves down onto a soft ball resting on a
// floor, presses it, and circles while pressing. Every iteration advances the world by 1 ms (as
// many engine steps as dt needs), reads the force the body exerted on the proxy over that
// millisecond, moves the proxy (mass m_p, semi-implicit Euler) under the coupling and that
// force, and computes the force the device would display (minus the coupling force).
//
//   haptic_loop [--size N] [--voxel H] [--youngs E] [--seconds T] [--threads N] [--integrator K]
//               [--csv FILE]
//
// Prints the body, dt, steps per iteration and the time per iteration (median, 99th percentile,
// max, standard deviation = jitter, iterations over 1 ms) as one JSON object; --csv writes one
// row per iteration (time, device, proxy, force on the proxy, displayed force, wall time).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "gradel/layout.h"
#include "gradel/model.h"
#include "gradel/shapes.h"
#include "gradel/world.h"

using namespace gradel;

namespace {

struct Options {
  int size = 52;             ///< ball diameter [voxels]: ~20,000 vertices in the gradational layout
  Real voxel = 0.004;        ///< [m]
  Real youngs = 2e4;         ///< [Pa] soft tissue
  Real seconds = 2.0;        ///< [s] of device path
  int threads = 1;
  std::string integrator = "symplectic";
  std::string csv;
};

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "haptic_loop: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--size") o.size = std::atoi(value());
    else if (a == "--voxel") o.voxel = std::atof(value());
    else if (a == "--youngs") o.youngs = std::atof(value());
    else if (a == "--seconds") o.seconds = std::atof(value());
    else if (a == "--threads") o.threads = std::atoi(value());
    else if (a == "--integrator") o.integrator = value();
    else if (a == "--csv") o.csv = value();
    else {
      std::fprintf(stderr, "haptic_loop: unknown option %s (see the comment at the top of examples/haptic_loop.cpp)\n",
                   a.c_str());
      std::exit(2);
    }
  }
  if (o.size < 2 || !(o.voxel > 0) || !(o.youngs > 0) || !(o.seconds > 0) || o.threads < 1) {
    std::fprintf(stderr, "haptic_loop: --size >= 2, --voxel, --youngs, --seconds > 0, --threads >= 1\n");
    std::exit(2);
  }
  return o;
}

// The device: 5 % of the diameter above the ball's top, down 15 % of the diameter in 0.5 s (a
// press of 10 %), then circling with a radius of a fifth of the diameter at 1 turn per second.
Vec3 devicePosition(Real t, const Vec3& top, Real diameter) {
  const Real down = 0.15 * diameter * std::min(Real(1), t / 0.5);
  const Real r = 0.2 * diameter * std::min(Real(1), std::max(Real(0), t - 0.5));
  const Real phase = 2 * M_PI * std::max(Real(0), t - 0.5);
  return top + Vec3(r * std::cos(phase), r * std::sin(phase), 0.05 * diameter - down);
}

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(q * double(v.size() - 1) + 0.5))];
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  try {
    const VoxelVolume volume = rasterize(presetShape("sphere", o.size, 3, o.voxel));
    const Layout layout = buildLayout(volume, LayoutKind::Gradational);
    MaterialSettings material;
    material.youngsModulus = o.youngs;
    auto model = std::make_shared<const RestModel>(buildRestModel(layout, volume, material, Vec3::Zero()));
    SimulationSettings sim;
    sim.gravity = Vec3(0, 0, -9.81);
    sim.damping = 5;
    sim.threads = o.threads;
    sim.integrator = parseIntegratorKind(o.integrator);
    if (sim.integrator == IntegratorKind::Implicit || sim.integrator == IntegratorKind::LargeStep) sim.dt = 1e-3;
    const Real diameter = o.size * o.voxel;
    DomainSettings floor;
    floor.enabled = true;
    floor.min = Vec3(-diameter, -diameter, 0), floor.max = Vec3(2 * diameter, 2 * diameter, 3 * diameter);
    floor.restitution = 0;
    World world(model, sim, floor, {});
    ManipulatorSettings tool;
    tool.radius = 0.1 * diameter;
    tool.restitution = 0;
    tool.friction = 0.3;
    // The ball first settles on the floor (untimed; a soft ball sags under its weight), then the
    // device starts above its top.
    const size_t k = world.addManipulator(tool, Vec3(0.5 * diameter, 0.5 * diameter, 2.5 * diameter));
    world.advanceTo(0.5);
    Real height = 0;
    for (const Vec3& x : world.state().positions) height = std::max(height, x.z());
    const Vec3 top(0.5 * diameter, 0.5 * diameter, height + tool.radius);
    Vec3 proxy = devicePosition(0, top, diameter), proxyVelocity = Vec3::Zero();
    world.setManipulatorPose(k, proxy, proxyVelocity);

    // Virtual coupling: a stiffness that lets the ball's weight (a few N) move the proxy by a
    // millimetre or so, a proxy of 20 g, and critical damping of that pair.
    const Real period = 1e-3;  // 1 kHz
    const Real proxyMass = 0.02, stiffness = 2000, damping = 2 * std::sqrt(stiffness * proxyMass);
    const int steps = std::max(1, int(std::ceil(period / world.dt() - 1e-9)));
    const size_t iterations = size_t(std::llround(o.seconds / period));

    std::FILE* csv = o.csv.empty() ? nullptr : std::fopen(o.csv.c_str(), "w");
    if (!o.csv.empty() && !csv) {
      std::fprintf(stderr, "haptic_loop: cannot write %s: %s\n", o.csv.c_str(), std::strerror(errno));
      return 1;
    }
    if (csv)
      std::fprintf(csv,
                   "time,device_x,device_y,device_z,proxy_x,proxy_y,proxy_z,body_fx,body_fy,body_fz,display_fx,"
                   "display_fy,display_fz,iteration_seconds\n");
    std::vector<double> wall(iterations);
    Vec3 devicePrev = proxy;
    Real maxForce = 0;
    for (size_t it = 0; it < iterations; ++it) {
      const auto t0 = std::chrono::steady_clock::now();
      const Real t = Real(it + 1) * period;  // device time (the world's is 0.5 s later)
      const Vec3 device = devicePosition(t, top, diameter);
      const Vec3 deviceVelocity = (device - devicePrev) / period;
      devicePrev = device;
      // The engine: 1 ms with the proxy where the coupling put it, the force averaged over it.
      world.setManipulatorPose(k, proxy, proxyVelocity);
      world.restartForceAverage();
      for (int s = 0; s < steps; ++s) world.step();
      const Vec3 body = world.averageContactForces().manipulators[k].force;
      // The coupling: the proxy between the device's spring-damper and the body.
      const Vec3 coupling = stiffness * (device - proxy) + damping * (deviceVelocity - proxyVelocity);
      proxyVelocity += period * (coupling + body) / proxyMass;
      proxy += period * proxyVelocity;
      const Vec3 display = -coupling;  // what the device's motors would render to the hand
      const auto t1 = std::chrono::steady_clock::now();
      wall[it] = std::chrono::duration<double>(t1 - t0).count();
      maxForce = std::max(maxForce, body.norm());
      if (csv)
        std::fprintf(csv, "%.6g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", t, device.x(),
                     device.y(), device.z(), proxy.x(), proxy.y(), proxy.z(), body.x(), body.y(), body.z(),
                     display.x(), display.y(), display.z(), wall[it]);
    }
    if (csv && std::fclose(csv) != 0) {
      std::fprintf(stderr, "haptic_loop: cannot write %s\n", o.csv.c_str());
      return 1;
    }
    double mean = 0, var = 0;
    for (double w : wall) mean += w;
    mean /= double(wall.size());
    for (double w : wall) var += (w - mean) * (w - mean);
    const size_t over = size_t(std::count_if(wall.begin(), wall.end(), [&](double w) { return w > period; }));
    std::printf(
        "{\"vertices\": %zu, \"elements\": %zu, \"integrator\": \"%s\", \"dt\": %.4g, \"steps_per_iteration\": %d, "
        "\"threads\": %d, \"iterations\": %zu, \"median_ms\": %.4f, \"p99_ms\": %.4f, \"max_ms\": %.4f, "
        "\"jitter_std_ms\": %.4f, \"over_1ms\": %zu, \"max_force_N\": %.4g, \"weight_N\": %.4g}\n",
        model->numVertices(), model->numElements(), integratorKindName(world.settings().integrator), world.dt(), steps,
        o.threads, iterations, 1e3 * percentile(wall, 0.5), 1e3 * percentile(wall, 0.99),
        1e3 * *std::max_element(wall.begin(), wall.end()), 1e3 * std::sqrt(var / double(wall.size())), over, maxForce,
        model->totalMass * 9.81);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptic_loop: %s\n", e.what());
    return 1;
  }
  return 0;
}
