// gradel-bench: the speed of the explicit step, CSV on stdout (one row per configuration, medians
// of --reps repetitions), progress on stderr. Three kinds of rows (column `set`):
//  - real: what users run (scene_presets.h, realBenchScene): SI units, a sphere of fixed size
//    (finer n = smaller voxels), gravity, walls, a manipulator pressing it, a pin, and metrics +
//    stress once per 1/60 s output frame, over --moduli (Young's modulus, Pa);
//  - paper: the paper's Table 1 setting (sec. 3.4: k = 10000, one voxel's mass per vertex, no
//    gravity, walls or output), the comparison with the paper;
//  - scene: a scene file (--scene FILE), run as `gradel run` would, frames computed, not written;
//  - contact: two spheres of n voxels meeting head on (contactBenchScene, soft-soft contact, issue
//    12): the `contact_steps` steps after they touch, timed per repetition on a fresh world;
//    contact_stage_share = the body-contact stage's wall time / the steps' (the other rows: 0);
//    --contact-trace FILE writes every step of the first repetition (its contacts, lookups, the
//    lookups of vertices the stage's own corrections moved, rounds, the stage's and step's time).
//
//   gradel-bench [--sets real,paper,contact] [--shapes sphere,box] [--sizes 16,32,64,128,256]
//                [--layouts gradational,uniform] [--moduli 1e4,1e5,1e6] [--threads 1,2]
//                [--scene FILE] [--integrator NAME] [--load] [--reps 5] [--min-time 0.2]
//                [--find-realtime] [--contact-steps 40] [--contact-trace FILE]
//
// Columns: ns_per_vertex_step = wall time per step (frame work included) / unique vertices;
// ns_per_pair_step the same per element-vertex pair; real_time_factor = simulated seconds per
// wall second; bytes_per_vertex = every array of the model, state and scratch / unique
// vertices; load = 1 when --load ran one busy process beside the benchmark; state_hash = hash
// of positions and velocities after exactly 20 (paper, and large_step / implicit rows) or 200
// (explicit real, scene) steps, or the contact rows' contact_steps steps in contact: identical at
// any thread count; integrator = the one that ran (--integrator sets it for the real and scene
// rows: symplectic by default on the real rows, the scene's own on scene rows; large_step runs
// at dt = 1/60 s).
// --carve: instead of the step, the cost of one carving event (carve.h, carve_scene.h) on a
// gradational n^3 box (--sizes), a burr of radius 3 voxels at a new place on the top face each
// repetition: its own CSV (set = carve), medians in ms of the tool's voxel set, the event (full
// re-layout, rest model, state carried over), the re-layout and rest model alone, and the whole
// scene event (event + the world made again, World::replaceModel); the first scene event alone
// (the operator rule estimated from scratch: no warm start yet, stability_warm.h); the world's
// remake (scene event less the event); the smallest and largest ratio of the event's omega_max
// to the estimate from scratch on the same model (>= 1: dt errs short); ms per step after the
// events and of a world made from scratch on the same model and state (interleaved), and both dt.
// --drill: steady drilling (issue 30's second target): a gradational n^3 box of soft tissue (5 mm
// voxels, E = 3e4 Pa, on the floor under gravity, damping 5/s) and a burr of radius 3 voxels with
// "carve" that enters the top face and wanders down through it for 1 s (a circle of radius n/4
// voxels, one turn, down n/2 voxels), carving after every frame of 1/60 s as the viewer and
// `gradel run` can: its own CSV (set = drill): frames, frames with an event, voxels removed,
// wall seconds of the whole second (steps + events), real-time factor, median and largest event
// [ms], the vertices and dt at the end.
// --split: a body cut in two (carve_scene.h, pieces.h): a gradational n^3 box (5 mm voxels, no
// gravity), a blade in its middle plane x = n/2 taking every row of that layer but the lowest
// (one event), then the lowest (the event that splits it): its own CSV (set = split), medians in
// ms of the event before, the splitting event (event, both pieces laid out, the world made again
// with contact between them) and splitBody alone on the carved body; vertices and bodies after.
// --find-realtime with --sets real: for each modulus, the largest gradational real-scene sphere n
// that runs in real time with the integrator given (n doubled from 16, then bisected).
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "gradel/carve_scene.h"
#include "gradel/pieces.h"
#include "gradel/stability.h"
#include "gradel/shared/scene_presets.h"

using namespace gradel;
using Clock = std::chrono::steady_clock;

namespace {

struct Row {
  std::string set, shape, layout, integrator;
  double youngs = 0;  // [Pa], 0 for the paper setting (k instead)
  double poisson = 0;  // material.poisson_ratio
  int n = 0, threads = 0, load = 0;
  size_t elements = 0, vertices = 0, pairs = 0;
  double nsPerVertex = 0, nsPerPair = 0, stepsPerSecond = 0, dt = 0, rtf = 0, bytesPerVertex = 0, contactShare = 0;
  uint64_t hash = 0;
};

double medianOf(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double msSince(Clock::time_point t0) { return 1e3 * std::chrono::duration<double>(Clock::now() - t0).count(); }

// --carve: one row per size and thread count (see the top of this file).
void measureCarve(int n, int threads, int reps) {
  Scene scene;
  scene.bodies[0].shape = presetShape("box", n, 3, 0.005);
  scene.simulation.gravity = Vec3::Zero();
  scene.simulation.threads = threads;
  BuiltScene b = buildScene(scene);
  b.world->step();
  const Real h = 0.005, r = 3 * h;
  std::vector<double> tSet, tEvent, tLayout, tScene, tRemake, ratio;
  double tFirst = 0;
  size_t removed = 0, verticesBefore = b.world->model().numVertices();
  for (int k = 0; k < reps; ++k) {
    const Vec3 centre(h * (n / 4 + (k * 7) % (n / 2)), h * n, h * (n / 4 + (k * 5) % (n / 2)));
    auto t0 = Clock::now();
    size_t count = 0;
    const std::vector<uint8_t> mask = voxelsInSphere(carveInput(b, 0), centre, r, &count);
    tSet.push_back(msSince(t0));
    t0 = Clock::now();
    const CarvedBody c = carveBody(carveInput(b, 0), mask);
    tEvent.push_back(msSince(t0));
    t0 = Clock::now();
    const Layout l = buildLayout(c.volume, LayoutKind::Gradational);
    const RestModel m = buildRestModel(l, c.volume, b.bodies[0].model->material, b.bodies[0].model->origin);
    tLayout.push_back(msSince(t0));
    t0 = Clock::now();
    removed = carveSceneBody(b, 0, mask).removedVoxels;
    tScene.push_back(msSince(t0));
    if (k == 0) tFirst = tScene.back();
    tRemake.push_back(tScene.back() - tEvent.back());
    // The event's omega_max against the estimate from scratch on the same model (not timed).
    ratio.push_back(b.world->stabilityEstimate().omega / highestFrequency(b.world->model()).omega);
    b.world->step();
  }
  // The step after the events against a world made from scratch on the same model and state,
  // interleaved, 20 steps each, 5 rounds: ms per step (median), and dt.
  World fresh(b.bodies[0].model, b.world->settings(), b.world->domain(), {});
  fresh.state() = b.world->state();
  std::vector<double> tAfter, tScratch;
  for (int round = 0; round < 5; ++round) {
    auto t0 = Clock::now();
    for (int s = 0; s < 20; ++s) b.world->step();
    tAfter.push_back(msSince(t0) / 20);
    t0 = Clock::now();
    for (int s = 0; s < 20; ++s) fresh.step();
    tScratch.push_back(msSince(t0) / 20);
  }
  std::printf("carve,%d,%d,%zu,%zu,%zu,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.4f,%.4f,%.4f,%.4f,%.6g,%.6g\n", n, threads, removed,
              verticesBefore, b.world->model().numVertices(), medianOf(tSet), medianOf(tEvent), medianOf(tLayout),
              medianOf(tScene), tFirst, medianOf(tRemake), *std::min_element(ratio.begin(), ratio.end()),
              *std::max_element(ratio.begin(), ratio.end()), medianOf(tAfter), medianOf(tScratch), b.world->dt(),
              fresh.dt());
  std::fflush(stdout);
}

// --split: one row per size and thread count (see the top of this file).
void measureSplit(int n, int threads, int reps) {
  const Real h = 0.005;
  std::vector<double> tBefore, tSplit, tPieces;
  size_t vertices = 0, bodies = 0;
  for (int k = 0; k < reps; ++k) {
    Scene scene;
    scene.bodies[0].shape = presetShape("box", n, 3, h);
    scene.simulation.gravity = Vec3::Zero();
    scene.simulation.threads = threads;
    BuiltScene b = buildScene(scene);
    b.world->step();
    BladeSweep blade;  // normal -x through the centres of layer n/2, all rows but j = 0
    blade.axis = Vec3(0, 0, 1), blade.widthAxis = Vec3(0, 1, 0), blade.halfLength = n * h;
    blade.halfWidth = (n - 1) * h / 2;
    blade.from = blade.to = Vec3((n / 2 + 0.5) * h, (n + 1) * h / 2, n * h / 2);
    auto t0 = Clock::now();
    carveSceneBlade(b, blade);
    tBefore.push_back(msSince(t0));
    blade.halfWidth = 0.25 * h, blade.from = blade.to = Vec3((n / 2 + 0.5) * h, 0.5 * h, n * h / 2);
    const std::vector<uint8_t> mask = voxelsAlongBlade(carveInput(b, 0), blade);
    const CarvedBody c = carveBody(carveInput(b, 0), mask);
    CarveInput in;
    in.volume = &c.volume, in.layout = &c.layout, in.model = c.model.get();
    in.positions = c.positions.data(), in.velocities = c.velocities.data(), in.rotations = c.rotations.data();
    t0 = Clock::now();
    const std::vector<BodyPiece> pieces = splitBody(in);
    tPieces.push_back(msSince(t0));
    t0 = Clock::now();
    carveSceneBlade(b, blade);
    tSplit.push_back(msSince(t0));
    vertices = b.world->model().numVertices(), bodies = b.numBodies();
    if (pieces.size() != 2 || bodies != 2) throw std::runtime_error("--split: the box did not fall into two pieces");
  }
  std::printf("split,%d,%d,%zu,%zu,%.3f,%.3f,%.3f\n", n, threads, vertices, bodies, medianOf(tBefore), medianOf(tSplit),
              medianOf(tPieces));
  std::fflush(stdout);
}

// --drill: one row per size and thread count (see the top of this file).
void measureDrill(int n, int threads) {
  const Real h = 0.005, side = n * h;
  Scene scene;
  scene.bodies[0].shape = presetShape("box", n, 3, h);
  scene.bodies[0].position = Vec3(-side / 2, 0, -side / 2);
  scene.bodies[0].material.youngsModulus = 3e4;
  scene.simulation.damping = 5;
  scene.simulation.threads = threads;
  scene.domain.enabled = true;
  scene.domain.min = Vec3(-1, 0, -1), scene.domain.max = Vec3(1, 1, 1);
  scene.domain.friction = 0.8, scene.domain.restitution = 0;
  ManipulatorSettings burr;
  burr.radius = 3 * h, burr.carve = true, burr.restitution = 0, burr.friction = 0.3;
  constexpr int kKeys = 24;
  for (int k = 0; k <= kKeys; ++k) {  // one turn of a circle of radius n/4 voxels, from above the top face down n/2
    const Real t = Real(k) / kKeys, a = 2 * M_PI * t;
    burr.path.keys.push_back({t, Vec3(0.25 * side * std::cos(a), side + burr.radius - 0.5 * side * t,
                                      0.25 * side * std::sin(a)), std::nullopt});
  }
  scene.manipulators = {burr};
  BuiltScene b = buildScene(scene);
  std::vector<Vec3> previous;
  std::vector<double> eventMs;
  constexpr int kFrames = 60;  // 1 s at 1/60 s
  size_t removed = 0;
  const auto t0 = Clock::now();
  for (int f = 1; f <= kFrames; ++f) {
    b.world->advanceTo(f / 60.0);
    const auto e0 = Clock::now();
    size_t voxels = 0;
    for (const CarveEvent& e : carveWithManipulators(b, previous)) voxels += e.removedVoxels;
    if (voxels) eventMs.push_back(msSince(e0)), removed += voxels;
  }
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  std::printf("drill,%d,%d,%d,%zu,%zu,%.4f,%.3g,%.3f,%.3f,%zu,%.4g\n", n, threads, kFrames, eventMs.size(), removed,
              wall, b.world->time() / wall, eventMs.empty() ? 0.0 : medianOf(eventMs),
              eventMs.empty() ? 0.0 : *std::max_element(eventMs.begin(), eventMs.end()),
              b.world->model().numVertices(), b.world->dt());
  std::fflush(stdout);
}

template <class T>
std::vector<T> splitList(const std::string& s, T (*conv)(const std::string&)) {
  std::vector<T> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(conv(item));
  return out;
}

// A busy process beside the benchmark (--load): what a user's other programs do to it.
struct BusyProcess {
  pid_t pid = -1;
  void start() {
    pid = fork();
    if (pid == 0) {
      volatile unsigned long x = 0;
      for (;;) x = x + 1;
    }
  }
  ~BusyProcess() {
    if (pid > 0) kill(pid, SIGKILL), waitpid(pid, nullptr, 0);
  }
};

// Times `reps` repetitions of steps on a built world, frame work (metrics + stress, as
// `gradel run` does per written frame) every frameInterval simulated seconds (0: none), after
// `hashSteps` steps that fix the state hash.
// The row's time figures from the median of the repetitions' seconds per step.
void setStepTime(Row& r, std::vector<double>& perStep) {
  std::sort(perStep.begin(), perStep.end());
  const double t = perStep[perStep.size() / 2];
  r.nsPerVertex = t * 1e9 / double(r.vertices);
  r.nsPerPair = t * 1e9 / double(r.pairs);
  r.stepsPerSecond = 1.0 / t;
  r.rtf = r.dt * r.stepsPerSecond;
}

void timeSteps(World& w, Row& r, int hashSteps, double frameInterval, int reps, double minTime) {
  for (int i = 0; i < hashSteps; ++i) w.step();
  r.hash = w.stateHash();
  r.elements = w.model().numElements(), r.vertices = w.model().numVertices(), r.pairs = w.model().numPairs();
  r.dt = w.dt();
  r.bytesPerVertex = double(w.memoryBytes()) / double(r.vertices);
  double nextFrame = frameInterval > 0 ? (std::floor(w.time() / frameInterval) + 1) * frameInterval : INFINITY;
  std::vector<Real> stress;
  Real sink = 0;
  auto run = [&](int steps) {
    for (int i = 0; i < steps; ++i) {
      w.step();
      if (w.time() >= nextFrame - 0.5 * w.dt()) {
        sink += w.metrics(&stress).kineticEnergy;
        nextFrame += frameInterval;
      }
    }
  };
  // Steps per repetition: enough for minTime seconds, from a calibration run.
  int steps = 1;
  for (;;) {
    const auto t0 = Clock::now();
    run(steps);
    const double s = std::chrono::duration<double>(Clock::now() - t0).count();
    if (s >= 0.25 * minTime || steps >= (1 << 20)) {
      steps = std::max(1, int(steps * minTime / std::max(s, 1e-9)));
      break;
    }
    steps *= 4;
  }
  std::vector<double> perStep;
  for (int k = 0; k < reps; ++k) {
    const auto t0 = Clock::now();
    run(steps);
    perStep.push_back(std::chrono::duration<double>(Clock::now() - t0).count() / steps);
  }
  if (!std::isfinite(sink)) std::fprintf(stderr, "warning: non-finite energy in %s\n", r.shape.c_str());
  setStepTime(r, perStep);
}

Row measure(const std::string& shape, int n, LayoutKind layout, int threads, int reps, double minTime) {
  BuiltScene b = buildScene(paperBenchScene(shape, n, layout, threads));
  for (BuiltBody& body : b.bodies)  // build inputs are not part of the running simulation's memory
    body.layout = Layout(), body.volume = VoxelVolume();
  preparePaperBench(*b.world);
  Row r;
  r.set = "paper", r.shape = shape, r.layout = layoutKindName(layout), r.n = n, r.threads = threads;
  r.integrator = integratorKindName(b.world->settings().integrator);
  timeSteps(*b.world, r, 20, 0, reps, minTime);
  return r;
}

Row measureScene(const Scene& scene, const std::string& set, int threads, int reps, double minTime) {
  Scene sc = scene;
  sc.simulation.threads = threads;
  BuiltScene b = buildScene(sc);
  for (BuiltBody& body : b.bodies) body.layout = Layout(), body.volume = VoxelVolume();
  Row r;
  r.set = set, r.shape = sc.name, r.layout = layoutKindName(sc.bodies[0].layout), r.threads = threads;
  r.integrator = integratorKindName(b.world->settings().integrator);
  r.n = sc.bodies[0].source ? 0 : sc.bodies[0].shape.dims[0];
  r.youngs = sc.bodies[0].material.scaling == Scaling::Consistent ? sc.bodies[0].material.youngsModulus : 0;
  r.poisson = sc.bodies[0].material.poissonRatio;
  // 200 explicit steps, 20 frame-size steps (1/3 s): the hash's point.
  const IntegratorKind k = b.world->settings().integrator;
  const bool frameStep = k == IntegratorKind::LargeStep || k == IntegratorKind::Implicit;
  timeSteps(*b.world, r, frameStep ? 20 : 200, sc.output.frameInterval, reps, minTime);
  return r;
}

// Two spheres in contact: per repetition a fresh world stepped until they touch, then `steps`
// steps timed (wall clock of the steps and of the body-contact stage, BodyContactStats::seconds);
// the medians of the repetitions. The hash after the timed steps (the same in every repetition).
// With `trace`: the first repetition's steps, one CSV row each (--contact-trace).
Row measureContact(int n, int threads, int steps, int reps, std::FILE* trace) {
  Row r;
  r.set = "contact", r.shape = "two-spheres", r.n = n, r.threads = threads, r.layout = "gradational";
  std::vector<double> perStep, share;
  for (int k = 0; k < reps; ++k) {
    BuiltScene b = buildScene(contactBenchScene(n, threads));
    World& w = *b.world;
    r.integrator = integratorKindName(w.settings().integrator);
    for (int i = 0; i < 100000 && w.bodyContactStats().contacts == 0; ++i) w.step();  // until they touch
    double stage = 0;
    const auto t0 = Clock::now();
    for (int i = 0; i < steps; ++i) {
      const auto s0 = Clock::now();
      w.step();
      const BodyContactStats& st = w.bodyContactStats();
      stage += st.seconds;
      if (trace && k == 0)
        std::fprintf(trace, "%d,%d,%d,%zu,%zu,%zu,%zu,%d,%d,%d,%.1f,%.1f\n", n, threads, i + 1, st.contacts, st.warm,
                     st.candidates, st.movedLookups, st.rounds, st.rebuilds, st.takeBacks, 1e6 * st.seconds,
                     1e6 * std::chrono::duration<double>(Clock::now() - s0).count());
    }
    const double total = std::chrono::duration<double>(Clock::now() - t0).count();
    perStep.push_back(total / steps), share.push_back(stage / total);
    r.hash = w.stateHash();
    r.elements = w.model().numElements(), r.vertices = w.model().numVertices(), r.pairs = w.model().numPairs();
    r.dt = w.dt();
    r.bytesPerVertex = double(w.memoryBytes()) / double(r.vertices);
  }
  setStepTime(r, perStep);
  std::sort(share.begin(), share.end());
  r.contactShare = share[share.size() / 2];
  return r;
}

void printHeader() {
  std::printf(
      "set,shape,n,layout,youngs_modulus_pa,threads,load,elements,unique_vertices,pairs,ns_per_vertex_step,"
      "ns_per_pair_step,steps_per_second,dt_s,real_time_factor,bytes_per_vertex,state_hash,integrator,"
      "contact_stage_share,poisson_ratio\n");
}

void printRow(const Row& r) {
  std::printf("%s,%s,%d,%s,%.3g,%d,%d,%zu,%zu,%zu,%.3f,%.3f,%.1f,%.6g,%.4g,%.1f,%016llx,%s,%.3f,%.3g\n", r.set.c_str(),
              r.shape.c_str(), r.n, r.layout.c_str(), r.youngs, r.threads, r.load, r.elements, r.vertices, r.pairs,
              r.nsPerVertex, r.nsPerPair, r.stepsPerSecond, r.dt, r.rtf, r.bytesPerVertex,
              static_cast<unsigned long long>(r.hash), r.integrator.c_str(), r.contactShare, r.poisson);
  std::fflush(stdout);
}

// Largest gradational sphere that runs in real time (real_time_factor >= 1) at `threads`: the
// real-time factor falls monotonically with n, so double n from 32 until it drops below 1, then
// bisect the bracket down to 2 voxels.
void findRealtime(int threads, int reps, double minTime) {
  Row best;
  auto ok = [&](int n) {
    const Row r = measure("sphere", n, LayoutKind::Gradational, threads, reps, minTime);
    std::fprintf(stderr, "  sphere %d: %zu elements, %zu vertices, real-time factor %.3f\n", n, r.elements, r.vertices,
                 r.rtf);
    std::printf("# search: sphere %d, %zu elements, %zu unique vertices, real-time factor %.4f\n", n, r.elements,
                r.vertices, r.rtf);
    if (r.rtf >= 1 && r.elements > best.elements) best = r;
    return r.rtf >= 1;
  };
  int lo = 12, hi = 32;
  if (!ok(lo)) {
    std::printf("# no sphere runs in real time at %d threads\n", threads);
    return;
  }
  while (hi <= 1024 && ok(hi)) lo = hi, hi *= 2;
  while (hi - lo > 2) {
    const int mid = (lo + hi) / 2;
    (ok(mid) ? lo : hi) = mid;
  }
  std::printf(
      "# largest real-time gradational sphere at %d threads: n = %d, %zu elements, %zu unique vertices, "
      "real-time factor %.3f (n = %d is not real time)\n",
      threads, best.n, best.elements, best.vertices, best.rtf, hi);
  printRow(best);
}

// Largest gradational real-scene sphere (realBenchScene) in real time at modulus E with `scene`'s
// integrator settings applied: n doubled from 16 while real time, then bisected to 2 voxels.
void findRealtimeReal(double E, const std::optional<IntegratorKind>& integrator, int threads, int reps,
                      double minTime) {
  Row best;
  auto ok = [&](int n) {
    Scene sc = realBenchScene(n, E, LayoutKind::Gradational);
    if (integrator) sc.simulation.integrator = *integrator;
    const Row r = measureScene(sc, "real", threads, reps, minTime);
    std::fprintf(stderr, "  real sphere %d E %.3g: real-time factor %.3f\n", n, E, r.rtf);
    std::printf("# search: real sphere %d, E %.3g Pa, %s, %zu unique vertices, real-time factor %.4f\n", n, E,
                r.integrator.c_str(), r.vertices, r.rtf);
    if (r.rtf >= 1 && r.n > best.n) best = r;
    return r.rtf >= 1;
  };
  int lo = 8, hi = 16;
  if (!ok(lo)) {
    std::printf("# no real-scene sphere runs in real time at E %.3g Pa, %d threads\n", E, threads);
    return;
  }
  while (hi <= 512 && ok(hi)) lo = hi, hi *= 2;
  while (hi - lo > 2) {
    const int mid = (lo + hi) / 2;
    (ok(mid) ? lo : hi) = mid;
  }
  std::printf("# largest real-time real-scene sphere at E %.3g Pa, %d threads, %s: n = %d (n = %d is not)\n", E,
              threads, best.integrator.c_str(), best.n, hi);
  printRow(best);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"gradel-bench: speed of real scenes and of the paper's Table 1 setting, CSV on stdout"};
  std::string sets = "real,paper", shapes = "sphere,box", sizes = "16,32,64,128,256", layouts = "gradational,uniform",
              moduli = "1e4,1e5,1e6", poissonRatios = "0", threads = "1,2", sceneFile, integratorName;
  int reps = 5, contactSteps = 40;
  std::string contactTrace;
  double minTime = 0.2, maxPairs = 4.0e7;
  bool findRt = false, load = false, carve = false, drill = false, split = false;
  app.add_option("--sets", sets,
                 "Comma-separated: real (SI scenes with gravity, walls, contact, pins, metrics), paper, contact "
                 "(two spheres in soft-soft contact)");
  app.add_option("--contact-steps", contactSteps, "contact set: steps timed after the spheres touch")
      ->check(CLI::Range(1, 100000));
  app.add_option("--contact-trace", contactTrace,
                 "contact set: write each step of the first repetition to this CSV file (contacts, lookups, the "
                 "stage's and the step's time)");
  app.add_option("--shapes", shapes, "paper set: comma-separated shapes (sphere, box); the real set is a sphere");
  app.add_option("--sizes", sizes, "Comma-separated grid sizes n (voxels)");
  app.add_option("--layouts", layouts, "Comma-separated: gradational, uniform, voxel");
  app.add_option("--moduli", moduli, "real set: comma-separated Young's moduli [Pa]");
  app.add_option("--poisson-ratios", poissonRatios,
                 "real set: comma-separated Poisson's ratios (material.poisson_ratio; dt = auto follows them)");
  app.add_option("--threads", threads, "Comma-separated thread counts");
  app.add_option("--scene", sceneFile,
                 "Also time this scene file (frames computed at its frame_interval, not written)");
  app.add_option("--integrator", integratorName,
                 "Integrator of the real and scene rows (symplectic, large_step, auto, ...; default: the scene's)");
  app.add_flag("--load", load, "Run one busy process beside the benchmark (a machine with other work on it)");
  app.add_option("--reps", reps, "Repetitions (the median is reported)")->check(CLI::Range(1, 1000));
  app.add_option("--min-time", minTime, "Seconds per repetition")->check(CLI::Range(0.001, 100.0));
  app.add_option("--max-pairs", maxPairs, "Skip configurations with more element-vertex pairs (memory)");
  app.add_flag("--find-realtime", findRt,
               "Also search the largest real-time gradational sphere at the largest thread count (paper setting; "
               "with --sets real: the real scene at each modulus, with --integrator)");
  app.add_flag("--carve", carve,
               "Only the cost of one carving event per --sizes and --threads (its own CSV, set = carve)");
  app.add_flag("--drill", drill,
               "Only steady drilling: a burr carving every frame through an n^3 box for 1 s per --sizes and "
               "--threads (its own CSV, set = drill)");
  app.add_flag("--split", split,
               "Only the cost of the carving event that cuts an n^3 box in two per --sizes and --threads (its own "
               "CSV, set = split)");
  CLI11_PARSE(app, argc, argv);
  // --drill and --carve: their own CSV, one row per --sizes and --threads.
  auto eachSizeAndThreads = [&](const char* header, auto&& row) {
    try {
      std::printf("%s\n", header);
      for (int n : splitList<int>(sizes, [](const std::string& x) { return std::stoi(x); }))
        for (int t : splitList<int>(threads, [](const std::string& x) { return std::stoi(x); })) row(n, t);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "gradel-bench: %s\n", e.what());
      return 2;
    }
    return 0;
  };
  if (drill)
    return eachSizeAndThreads("set,n,threads,frames,frames_with_event,removed_voxels,wall_s,real_time_factor,"
                              "ms_event_median,ms_event_max,vertices_after,dt_after_s",
                              [](int n, int t) { measureDrill(n, t); });
  if (split)
    return eachSizeAndThreads("set,n,threads,vertices_after,bodies_after,ms_event_before,ms_split_event,ms_split_body",
                              [&](int n, int t) { measureSplit(n, t, reps); });
  if (carve)
    return eachSizeAndThreads("set,n,threads,removed_voxels,vertices_before,vertices_after,ms_tool_voxels,ms_event,"
                              "ms_relayout_and_model,ms_scene_event,ms_scene_event_first,ms_world_remake,"
                              "omega_ratio_min,omega_ratio_max,ms_step_after,ms_step_scratch,dt_after,dt_scratch",
                              [&](int n, int t) { measureCarve(n, t, reps); });
  try {
    auto str = [](const std::string& s) { return s; };
    const auto setList = splitList<std::string>(sets, str);
    const auto shapeList = splitList<std::string>(shapes, str);
    const auto sizeList = splitList<int>(sizes, [](const std::string& s) { return std::stoi(s); });
    const auto layoutList = splitList<LayoutKind>(layouts, [](const std::string& s) { return parseLayoutKind(s); });
    const auto moduliList = splitList<double>(moduli, [](const std::string& s) { return std::stod(s); });
    const auto poissonList = splitList<double>(poissonRatios, [](const std::string& s) { return std::stod(s); });
    const auto threadList = splitList<int>(threads, [](const std::string& s) { return std::stoi(s); });
    for (const std::string& set : setList)
      if (set != "real" && set != "paper" && set != "contact")
        throw std::runtime_error("--sets: unknown set '" + set + "' (real, paper, contact)");
    std::optional<IntegratorKind> integrator;
    if (!integratorName.empty()) integrator = parseIntegratorKind(integratorName);
    std::optional<Scene> scene;
    if (!sceneFile.empty()) scene = loadScene(sceneFile);
    if (scene && integrator) scene->simulation.integrator = *integrator;
    BusyProcess busy;
    if (load) busy.start();
    auto emit = [&](Row r) {
      r.load = load ? 1 : 0;
      printRow(r);
    };
    auto tooBig = [&](const std::string& shape, int n, LayoutKind layout) {
      // Pair count estimate from the voxel count, to skip what would not fit in memory.
      const double voxels = double(n) * n * n * (shape == "sphere" ? 0.5236 : 1.0);
      const double pairs = layout == LayoutKind::Voxel ? 8 * voxels : layout == LayoutKind::Uniform ? voxels : 0;
      if (pairs <= maxPairs) return false;
      std::printf("# skipped %s %d %s: ~%.0f pairs > --max-pairs\n", shape.c_str(), n, layoutKindName(layout), pairs);
      return true;
    };
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> trace(nullptr, std::fclose);
    if (!contactTrace.empty()) {
      trace.reset(std::fopen(contactTrace.c_str(), "w"));
      if (!trace) throw std::runtime_error("--contact-trace: cannot write '" + contactTrace + "'");
      std::fprintf(trace.get(),
                   "n,threads,step,contacts,warm,lookups,moved_lookups,rounds,rebuilds,take_backs,stage_us,step_us\n");
    }
    printHeader();
    if (scene)
      for (int t : threadList) {
        std::fprintf(stderr, "scene %s threads %d\n", sceneFile.c_str(), t);
        emit(measureScene(*scene, "scene", t, reps, minTime));
      }
    for (const std::string& set : setList)
      for (int n : sizeList) {
        if (set == "contact") {
          for (int t : threadList) {
            std::fprintf(stderr, "contact two spheres %d threads %d\n", n, t);
            emit(measureContact(n, t, contactSteps, reps, trace.get()));
          }
          continue;
        }
        for (LayoutKind layout : layoutList) {
          if (set == "real") {
            if (tooBig("sphere", n, layout)) continue;
            for (double E : moduliList)
              for (double nu : poissonList)
                for (int t : threadList) {
                  std::fprintf(stderr, "real sphere %d %s E %.3g nu %.3g threads %d\n", n, layoutKindName(layout), E, nu, t);
                  Scene sc = realBenchScene(n, E, layout);
                  sc.bodies[0].material.poissonRatio = nu;
                  if (integrator) sc.simulation.integrator = *integrator;
                  emit(measureScene(sc, "real", t, reps, minTime));
                }
            continue;
          }
          for (const std::string& shape : shapeList) {
            if (tooBig(shape, n, layout)) continue;
            for (int t : threadList) {
              std::fprintf(stderr, "paper %s %d %s threads %d\n", shape.c_str(), n, layoutKindName(layout), t);
              emit(measure(shape, n, layout, t, reps, minTime));
            }
          }
        }
      }
    const int maxThreads = *std::max_element(threadList.begin(), threadList.end());
    if (findRt && std::find(setList.begin(), setList.end(), "real") != setList.end())
      for (double E : moduliList) findRealtimeReal(E, integrator, maxThreads, reps, minTime);
    else if (findRt)
      findRealtime(maxThreads, reps, minTime);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gradel-bench: %s\n", e.what());
    return 2;
  }
  return 0;
}
