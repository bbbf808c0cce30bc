// gradel: command-line front end.
//   gradel layout --shape sphere --size 12 [--dim 2|3] [--layout ...] [--json]
//   gradel run SCENE.json [--out DIR] [--duration S] [--threads N] [--max-steps N]
//   gradel render SCENE.json [--out DIR] [--frames N] [--size WxH] ...   (render_command.h)
//   gradel --version
// Exit codes: 0 ok, 1 internal error, 2 bad input (one line on stderr, nothing written),
// 3 simulation diverged numerically (energy over 10x what was supplied, contacts' work included, or
// non-finite numbers; nothing written), 4 no OpenGL for `render`, 5 writing the result failed
// (disk full, read-only; nothing written), 128 + signal when interrupted by SIGINT (130),
// SIGTERM (143) or SIGHUP (129) (nothing written).
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "gradel/carve_scene.h"
#include "gradel/divergence.h"
#include "gradel/layout.h"
#include "gradel/output.h"
#include "gradel/overlaps.h"
#include "gradel/scene.h"
#include "gradel/shapes.h"
#include "gradel/shared/frame_loop.h"
#include "gradel/shared/run_budget.h"
#include "gradel/size_limits.h"
#include "gradel/slow_stage.h"
#ifdef GRADEL_WITH_RENDER
#include "render_cli.h"
#endif

#ifndef GRADEL_VERSION
#define GRADEL_VERSION "0.1.0"
#endif

namespace {

using gradel::InputError;
using gradel::Real;
using nlohmann::json;
namespace fs = std::filesystem;

constexpr int kExitInternal = 1;
constexpr int kExitInput = 2;
constexpr int kExitDiverged = 3;
constexpr int kExitIo = 5;

struct Diverged : std::runtime_error {
  using std::runtime_error::runtime_error;
};
/// Exit code 128 + signal, as shells report it.
struct Interrupted : std::runtime_error {
  Interrupted(int signal, const std::string& what) : std::runtime_error(what), signal(signal) {}
  int signal;
};

// Messages go out as exactly one line.
std::string oneLine(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  std::replace(s.begin(), s.end(), '\r', ' ');
  return s;
}

// ---- layout -------------------------------------------------------------------

struct LayoutOptions {
  std::string shape = "sphere";
  int size = 12;  // the paper's real-time limit: a sphere inscribed in 12^3 voxels (sec. 3.4)
  int dim = 3;
  std::string layout = "gradational";
  bool json = false;
};

double ratio(size_t a, size_t b) { return b == 0 ? 0.0 : double(a) / double(b); }

int runLayout(const LayoutOptions& o) {
  const gradel::LayoutKind kind = gradel::parseLayoutKind(o.layout);
  if (o.size < 1 || o.size > gradel::kMaxGridEdge)
    throw InputError("--size: " + std::to_string(o.size) + " is out of range (expected 1 to " +
                     std::to_string(gradel::kMaxGridEdge) + " voxels, and at most 1024 in 3D)");
  const gradel::ShapeSpec spec = gradel::presetShape(o.shape, o.size, o.dim);
  // Sizes are checked before anything big is allocated (size_limits.h).
  const gradel::SizeLimits limits;
  gradel::checkVolumeSize(spec.dims, spec.dim, limits, "--size");
  gradel::VoxelVolume volume;
  {
    gradel::SlowStage stage("voxelising the " + o.shape);
    volume = gradel::rasterize(spec);
  }
  gradel::checkLayoutSize(volume, kind, limits, "--size");
  gradel::Layout layout;
  {
    gradel::SlowStage stage("building the " + o.layout + " layout of " + std::to_string(volume.countFilled()) +
                            " voxels");
    layout = gradel::buildLayout(volume, kind);
  }
  const gradel::LayoutStats s = gradel::layoutStats(layout, volume);
  // The voxel layout (one element per voxel) is the baseline the paper's savings refer to;
  // counted, not built.
  const gradel::LayoutStats base = kind == gradel::LayoutKind::Voxel ? s : gradel::voxelLayoutStats(volume);

  if (o.json) {
    json j;
    j["shape"] = o.shape;
    j["size"] = o.size;
    j["dim"] = o.dim;
    j["layout"] = gradel::layoutKindName(kind);
    j["voxels"] = s.voxels;
    j["elements"] = s.elements;
    j["elements_per_level"] = s.elementsPerLevel;
    j["unique_vertices"] = s.uniqueVertices;
    j["pairs"] = s.pairs;
    j["hanging_vertices"] = s.hangingVertices;
    j["hanging_pairs"] = s.hangingPairs;
    j["voxel_layout"] = {{"elements", base.elements}, {"unique_vertices", base.uniqueVertices}, {"pairs", base.pairs}};
    j["ratio_pairs"] = ratio(s.pairs, base.pairs);
    j["ratio_unique_vertices"] = ratio(s.uniqueVertices, base.uniqueVertices);
    std::cout << j.dump(2) << "\n";
    return 0;
  }

  auto line = [](const std::string& label, const std::string& value) {
    std::printf("%-24s %s\n", label.c_str(), value.c_str());
  };
  auto withRatio = [](size_t v, size_t b) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%-10zu (voxel layout %zu, ratio %.3f)", v, b, ratio(v, b));
    return std::string(buf);
  };
  line("shape",
       o.shape + " " + std::to_string(o.size) + (o.dim == 3 ? "^3" : "^2") + " (" + std::to_string(o.dim) + "D)");
  line("layout", gradel::layoutKindName(kind));
  line("voxels", std::to_string(s.voxels));
  line("elements", withRatio(s.elements, base.elements));
  for (size_t l = 0; l < s.elementsPerLevel.size(); ++l)
    line("  level " + std::to_string(l) + " (edge " + std::to_string(kind == gradel::LayoutKind::Voxel ? 1u : 2u << l) +
             ")",
         std::to_string(s.elementsPerLevel[l]));
  line("unique vertices", withRatio(s.uniqueVertices, base.uniqueVertices));
  line("element-vertex pairs", withRatio(s.pairs, base.pairs));
  line("hanging vertices", std::to_string(s.hangingVertices));
  line("hanging pairs", std::to_string(s.hangingPairs));
  return 0;
}

// ---- run ------------------------------------------------------------------------

struct RunOptions {
  std::string scene;
  std::string out;
  std::optional<double> duration;
  std::optional<int> threads;
  std::optional<double> maxSteps;
};

// The signal that asked the run to stop (SIGINT, SIGTERM, SIGHUP), 0 while none did.
volatile std::sig_atomic_t gSignal = 0;
extern "C" void onStopSignal(int sig) { gSignal = sig; }

// A one-line progress bar on stderr, only on a terminal, redrawn at most 10 times a second.
class Progress {
 public:
  Progress() : enabled_(::isatty(STDERR_FILENO) == 1), start_(Clock::now()), last_(start_) {}
  void update(double fraction) {
    if (!enabled_) return;
    const auto now = Clock::now();
    if (now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    fraction = std::clamp(fraction, 0.0, 1.0);
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    constexpr int kWidth = 30;
    const int filled = int(fraction * kWidth);
    std::string bar(size_t(filled), '#');
    bar.resize(kWidth, '.');
    char eta[32] = "--";
    if (fraction > 0) std::snprintf(eta, sizeof eta, "%.0f s", elapsed * (1 - fraction) / fraction);
    std::fprintf(stderr, "\r[%s] %5.1f%%  ETA %-10s", bar.c_str(), 100.0 * fraction, eta);
    std::fflush(stderr);
    drawn_ = true;
  }
  ~Progress() {
    if (drawn_) std::fprintf(stderr, "\r%*s\r", 60, "");  // leave a clean line for messages
  }

 private:
  using Clock = std::chrono::steady_clock;
  bool enabled_;
  Clock::time_point start_, last_;
  bool drawn_ = false;
};

std::string hex64(uint64_t h) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

// The run's step budget (run_budget.h) as a vertex limit per body, checked with the layout's
// counts before any layout is built (size_limits.h check 2): a body of size 1000 is refused in
// seconds instead of after building it. dt comes from a 4-voxel box of the first body's material
// and voxel size in the voxel layout (every element a voxel); a body's own dt is smaller (a
// gradational sphere's 0.6x), so the steps are at least that many, and the limit allows 2x the
// budget on top. None with --max-steps (steps only) or when the steps alone are over their limit.
gradel::SizeLimits runSizeLimits(const gradel::Scene& scene, Real duration, std::optional<double> maxSteps) {
  gradel::SizeLimits limits;
  if (maxSteps) return limits;
  gradel::Scene probe;
  probe.dim = scene.dim;
  probe.simulation = scene.simulation;
  probe.simulation.threads = 1;
  probe.bodies[0].material = scene.bodies[0].material;
  probe.bodies[0].layout = gradel::LayoutKind::Voxel;
  probe.bodies[0].shape = gradel::presetShape("box", 4, scene.dim, scene.bodies[0].shape.voxelSize);
  probe.bodies[0].material.regions.clear();
  Real dt = 0;
  try {
    dt = gradel::buildScene(probe).world->dt();
  } catch (const InputError&) {
    return limits;  // the scene's own build reports it
  }
  const double steps = std::ceil(duration / dt - 1e-9);
  if (steps > gradel::kDefaultMaxSteps) return limits;  // refused for its steps after the build, with the exact dt
  const double allowed = 2 * gradel::kDefaultMaxVertexSteps / std::max(1.0, steps);
  if (allowed >= 1e15) return limits;
  limits.maxVertices = uint64_t(allowed);
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "that a run of %g s allows (dt at most about %.3g s: at least %.3g steps; the budget of %.3g "
                "vertex-steps, with a margin of 2); use a smaller size, a larger voxel_size, a shorter duration, or "
                "pass --max-steps to run it anyway",
                duration, dt, steps, gradel::kDefaultMaxVertexSteps);
  limits.vertexLimitReason = buf;
  return limits;
}

int runScene(const RunOptions& o) {
  // Everything that can be wrong with the input is checked before anything is written.
  gradel::Scene scene = gradel::loadScene(o.scene);
  if (o.duration) {
    if (!(*o.duration > 0) || !std::isfinite(*o.duration))
      throw InputError("--duration: must be a positive number of seconds");
    scene.output.duration = *o.duration;
  }
  if (o.threads) {
    if (*o.threads < 1 || *o.threads > 1024) throw InputError("--threads: must be in [1, 1024]");
    scene.simulation.threads = *o.threads;
  }
  if (o.maxSteps && !(*o.maxSteps >= 1 && *o.maxSteps <= 1e18))
    throw InputError("--max-steps: must be a number of steps in [1, 1e18]");
  const Real duration = scene.output.duration;
  const Real interval = scene.output.frameInterval;

  gradel::BuiltScene built;
  try {
    built = gradel::buildScene(scene, runSizeLimits(scene, duration, o.maxSteps));
  } catch (const InputError& e) {
    throw e.at(o.scene);
  }
  gradel::World& world = *built.world;
  const gradel::RestModel& model = world.model();
  const Real dt = world.dt();

  // How long will it take? Refused beyond the budget unless --max-steps allows it (run_budget.h).
  try {
    gradel::checkRunBudget(gradel::estimateRun(duration, dt, model.numVertices(), scene.simulation.integrator), dt,
                           duration, o.maxSteps);
  } catch (const InputError& e) {
    throw e.at(o.scene);
  }
  // The frames (frame_loop.h): at t = 0, every frame_interval, the last one exactly at `duration`.
  gradel::FrameSchedule schedule;
  try {
    schedule = gradel::frameSchedule(0, duration, interval, dt);
  } catch (const InputError& e) {
    throw e.at(o.scene, "simulation.");
  }
  // Bodies placed overlapping each other, a manipulator or a wall: told, then separated at a
  // capped speed by the world (overlaps.h).
  {
    std::vector<std::string> names;
    for (size_t i = 0; i < built.numBodies(); ++i) names.push_back(built.bodies[i].name);
    for (const gradel::StartOverlap& ov : world.startOverlaps())
      std::fprintf(stderr, "gradel: %s: %s\n", o.scene.c_str(), gradel::describeStartOverlap(ov, world, names).c_str());
  }
  if (schedule.intervalRaisedToDt)
    std::fprintf(
        stderr,
        "gradel: %s: simulation.frame_interval %.3g s is shorter than dt = %.3g s; writing one frame per step\n",
        o.scene.c_str(), interval, dt);

  // SIGINT, SIGTERM and SIGHUP all stop the run the same way: nothing written, exit 128 + signal.
  // Installed before the output folder exists and restored after it is gone.
  gSignal = 0;
  struct RestoreHandlers {
    const int kSignals[3] = {SIGINT, SIGTERM, SIGHUP};
    void (*previous[3])(int);
    RestoreHandlers() {
      for (int i = 0; i < 3; ++i) previous[i] = std::signal(kSignals[i], onStopSignal);
    }
    ~RestoreHandlers() {
      for (int i = 0; i < 3; ++i) std::signal(kSignals[i], previous[i]);
    }
  } handlers;
  gradel::OutputDirectory dir(o.out.empty() ? fs::path("out") / scene.name : fs::path(o.out), "run.pvd");
  {
    std::error_code ec;
    fs::copy_file(o.scene, dir.file("scene.json"), ec);
    if (ec) throw gradel::IoError("cannot write " + dir.file("scene.json").string() + ": " + ec.message());
  }
  // Several bodies: one file per body and frame, all listed per time in run.pvd (parts), and
  // per frame a metrics row per body and one for the world (docs/scenes.md, "Output").
  const bool several = built.numBodies() > 1;
  // Carving manipulators (`"carve": true`, carve_scene.h) remove what they swept after every chunk
  // of steps; metrics.csv then carries the removed material (docs/carving.md, "Feedback").
  const bool carving = std::any_of(world.manipulators().begin(), world.manipulators().end(),
                                   [](const gradel::Manipulator& m) { return m.settings.carve; });
  gradel::MetricsCsv csv(dir.file("metrics.csv"), world.manipulators().size(), several, carving);
  std::vector<gradel::PvdFrame> pvd;
  size_t framesWritten = 0;
  Real maxPenetration = 0, maxStress = 0, maxStrain = 0;
  gradel::Metrics last;

  gradel::DivergenceGuard guard(gradel::energyBudget(world, duration));
  const gradel::DivergenceFacts facts = gradel::divergenceFacts(world, duration);
  // Frames go to the file system on the writer's thread while the next steps run; declared
  // after `dir`, so that an unwinding run waits for the file in flight before `dir` is removed.
  gradel::FrameFileWriter frameWriter;
  auto writeFrame = [&](size_t index) {
    std::vector<gradel::Real> elementStress, elementStrain;
    // One pass over the elements per frame.
    const std::vector<gradel::Metrics> each = world.bodyMetrics(&elementStress, &elementStrain);
    gradel::Metrics m = gradel::combineMetrics(each);
    m.contactForces = world.averageContactForces();  // what the bodies exert together (World::metrics)
    std::string warning;
    if (auto diverged = guard.check(m, gradel::suppliedWork(world), gradel::likelyCause(facts, m), &warning))
      throw Diverged(*diverged);
    if (!warning.empty()) std::fprintf(stderr, "gradel: %s: %s\n", o.scene.c_str(), warning.c_str());
    if (several) {
      for (size_t i = 0; i < each.size(); ++i) csv.append(built.bodies[i].name, each[i], /*forces=*/false);
      csv.append("all", m);
    } else {
      csv.append(m);
    }
    maxPenetration = std::max(maxPenetration, m.maxPenetration);
    maxStress = std::max(maxStress, m.maxStress), maxStrain = std::max(maxStrain, m.maxStrain);
    last = m;
    const std::vector<gradel::Real> vertexStress = world.vertexStress(elementStress);
    const std::vector<gradel::Real> vertexStrain = world.vertexStress(elementStrain);
    // A body cut into pieces becomes several bodies (carve_scene.h): from then on one file each.
    const bool named = built.numBodies() > 1;
    for (size_t i = 0; i < built.numBodies(); ++i) {
      const std::string name = gradel::frameFileName(index, named ? built.bodies[i].name : "");
      gradel::encodeVtu(frameWriter.buffer(), world.model(), world.state(), built.range(i), vertexStress,
                        elementStress, gradel::VtkEncoding::Raw, vertexStrain, elementStrain);
      frameWriter.submit(dir.file(name));
      pvd.push_back({world.time(), name, int(i), named ? built.bodies[i].name : ""});
    }
    ++framesWritten;
  };

  // Divergence, Ctrl-C and the progress bar are noticed within a frame (frame_loop.h).
  Progress progress;
  gradel::FrameLoopChecks checks;
  checks.afterChunk = [&] {
    if (!gradel::finiteState(world.state())) {
      char msg[160];
      std::snprintf(msg, sizeof msg, "simulation diverged at t=%.6g s (dt = %.3g s): non-finite numbers; ",
                    world.time(), dt);
      throw Diverged(msg + gradel::likelyCause(facts, last));
    }
    if (const int sig = gSignal)
      throw Interrupted(sig, std::string("interrupted by ") +
                                 (sig == SIGINT    ? "SIGINT"
                                  : sig == SIGTERM ? "SIGTERM"
                                                   : "SIGHUP") +
                                 "; nothing written");
  };
  checks.progress = [&](double fraction) { progress.update(fraction); };
  // Carving: after every chunk the tools' sweeps; an event is a chunk that removed voxels (the
  // world made again once), its wall time the tools' voxel sets, the re-layouts and the new World.
  std::vector<gradel::Vec3> carvePrevious;
  size_t carveEvents = 0, carveBodyEvents = 0, carvedVoxels = 0, carveNewBodies = 0;
  double carveSeconds = 0, carveEventSeconds = 0, carveEventMaxSeconds = 0;
  long long carveSteps = 0;  // events shorten dt: the steps counted per chunk at the chunk's dt
  Real chunkStart = world.time();
  if (carving) {
    checks.afterChunk = [&, check = checks.afterChunk] {
      check();
      carveSteps += std::llround((world.time() - chunkStart) / world.dt());
      const auto t0 = std::chrono::steady_clock::now();
      const std::vector<gradel::CarveEvent> events = gradel::carveWithManipulators(built, carvePrevious);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      carveSeconds += seconds;
      chunkStart = world.time();
      if (events.empty()) return;
      ++carveEvents, carveEventSeconds += seconds, carveEventMaxSeconds = std::max(carveEventMaxSeconds, seconds);
      for (const gradel::CarveEvent& e : events)
        ++carveBodyEvents, carvedVoxels += e.removedVoxels, carveNewBodies += e.pieces.size() - 1;
    };
  }
  const auto wallStart = std::chrono::steady_clock::now();
  gradel::runFrames(world, schedule, writeFrame, checks);
  frameWriter.finish();  // the wall time includes the last frame's write
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wallStart).count();
  csv.close();
  gradel::writePvd(dir.file("run.pvd"), pvd);
  dir.commit();

  json j;
  j["scene"] = scene.name;
  j["steps"] = carving ? carveSteps : std::llround(world.time() / dt);
  j["dt"] = dt;
  if (carving) j["final_dt"] = world.dt();  // dt = auto follows the carved body (World::replaceModel)
  j["dt_rule"] = world.dtRule();  // where dt came from: given, one frame, or the rule and its fraction
  j["integrator"] = gradel::integratorKindName(world.settings().integrator);
  if (!world.integratorChoice().empty()) j["integrator_choice"] = world.integratorChoice();  // why auto picked it
  j["simulated_seconds"] = world.time();
  j["frames"] = framesWritten;
  j["bodies"] = built.numBodies();
  j["wall_seconds"] = wall;
  j["real_time_factor"] = wall > 0 ? world.time() / wall : 0.0;
  j["elements"] = world.model().numElements();
  j["vertices"] = world.model().numVertices();
  j["pairs"] = world.model().numPairs();
  if (carving) {  // docs/carving.md, "Feedback"
    j["carve_events"] = carveEvents;            // chunks that removed voxels (the world made again once each)
    j["carve_body_events"] = carveBodyEvents;   // bodies that lost voxels, summed over the events
    j["carved_voxels"] = carvedVoxels;
    j["carve_new_bodies"] = carveNewBodies;  // bodies cut into pieces: one body per piece (carve_scene.h)
    gradel::RemovedMaterial total;
    for (const gradel::RemovedMaterial& r : world.removedMaterial()) total.volume += r.volume, total.mass += r.mass;
    j["carved_volume"] = total.volume;  // [m^3]
    j["carved_mass"] = total.mass;      // [kg]
    j["carve_seconds"] = carveSeconds;  // wall time of all the tools' sweeps, events or not
    j["carve_event_seconds"] = carveEventSeconds;         // of the events only (full re-layout each)
    j["carve_event_max_seconds"] = carveEventMaxSeconds;  // the slowest event
  }
  j["final_kinetic_energy"] = last.kineticEnergy;
  j["max_penetration"] = maxPenetration;
  j["max_stress"] = maxStress;  // [Pa] von Mises
  j["max_strain"] = maxStrain;  // [-]
  j["state_hash"] = hex64(world.stateHash());
  j["out"] = dir.target().string();
  std::cout << j.dump(2) << "\n";
  return 0;
}

// `gradel study FILE [options]`: the parameter study front (docs/study.md). The study runs in
// Python on Dask (gradel.study); this hands the arguments to `python3 -m gradel.study`, with the
// build tree's package first on the path when the program runs from a build tree (an installed
// package is found by Python itself). $GRADEL_PYTHON names another interpreter.
int runStudy(const std::vector<std::string>& args) {
  const char* python = std::getenv("GRADEL_PYTHON") ? std::getenv("GRADEL_PYTHON") : "/usr/bin/python3";
  std::error_code ec;
  const fs::path buildPython = fs::read_symlink("/proc/self/exe", ec).parent_path() / "python";
  if (!ec && fs::exists(buildPython / "gradel", ec)) {
    const char* old = std::getenv("PYTHONPATH");
    const std::string path = buildPython.string() + (old && *old ? ":" + std::string(old) : "");
    setenv("PYTHONPATH", path.c_str(), 1);
  }
  std::vector<std::string> argvStrings{python, "-m", "gradel.study"};
  argvStrings.insert(argvStrings.end(), args.begin(), args.end());
  std::vector<char*> argvPtrs;
  for (std::string& a : argvStrings) argvPtrs.push_back(a.data());
  argvPtrs.push_back(nullptr);
  std::cout.flush();
  execv(python, argvPtrs.data());
  std::cerr << "gradel: study: cannot start " << python << ": " << std::strerror(errno)
            << " (the study needs Python 3 with numpy and python3-distributed: scripts/setup)\n";
  return kExitInternal;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"gradel: gradational elastic elements from voxel volumes (Miyazaki et al. 2002)", "gradel"};
  app.set_version_flag("--version", std::string("gradel ") + GRADEL_VERSION);
  app.require_subcommand(1);

  LayoutOptions lo;
  CLI::App* layout = app.add_subcommand("layout", "Build an element layout from a preset shape and print its counts");
  layout->add_option("--shape", lo.shape, "box | sphere | cylinder (3D only)")->capture_default_str();
  layout->add_option("--size", lo.size, "Grid edge [voxels]; the shape is inscribed in size^dim voxels")
      ->capture_default_str();
  layout->add_option("--dim", lo.dim, "2 or 3")->capture_default_str();
  layout->add_option("--layout", lo.layout, "gradational | uniform | voxel")->capture_default_str();
  layout->add_flag("--json", lo.json, "Print one JSON object instead of text");

  RunOptions ro;
  CLI::App* run = app.add_subcommand("run", "Simulate a scene file and write frames, metrics and a JSON summary");
  run->add_option("scene", ro.scene, "Scene file (JSON, see docs/scenes.md)")->required();
  run->add_option("--out", ro.out, "Result directory (default: out/<scene name>)");
  run->add_option("--duration", ro.duration, "Simulated time [s] (overrides simulation.duration)");
  run->add_option("--threads", ro.threads, "Worker threads (overrides simulation.threads)");
  run->add_option("--max-steps", ro.maxSteps,
                  "Allow up to N time steps (default: refuse runs over 1e7 steps or 1e11 vertex-steps)");

  CLI::App* study = app.add_subcommand(
      "study",
      "Run a parameter study (a base scene and a grid of overrides) on a Dask cluster: gradel study FILE "
      "[--address tcp://HOST:8786] [--workers N] [--out DIR] (all options: gradel study --help)");
  study->prefix_command();  // everything after `study` goes to gradel.study, --help included
  study->set_help_flag();

#ifdef GRADEL_WITH_RENDER
  gradel::render::RenderCommandOptions rendo;
  CLI::App* render = gradel::render::addRenderCommand(app, rendo);
#endif

  // An unknown subcommand is named (CLI11 would only say that one is required).
  if (argc >= 2 && argv[1][0] != '-') {
    std::string names;
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
      known = known || sub->get_name() == argv[1];
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::cerr << "gradel: unknown subcommand '" << oneLine(argv[1]) << "' (expected one of " << names
                << "; see gradel --help)\n";
      return kExitInput;
    }
  }

  gradel::setSlowStageReports(true);  // a line on stderr for a layout or build that takes over a second
  try {
    app.parse(argc, argv);
    if (layout->parsed()) return runLayout(lo);
    if (study->parsed()) return runStudy(study->remaining());
#ifdef GRADEL_WITH_RENDER
    if (render->parsed()) return gradel::render::runRenderCommand(rendo);
#endif
    return runScene(ro);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    std::cerr << "gradel: " << oneLine(e.what()) << " (see gradel --help)\n";
    return kExitInput;
  } catch (const InputError& e) {
    std::cerr << "gradel: " << oneLine(e.what()) << "\n";
    return kExitInput;
  } catch (const Diverged& e) {
    std::cerr << "gradel: " << oneLine(e.what()) << "\n";
    return kExitDiverged;
  } catch (const Interrupted& e) {
    std::cerr << "gradel: " << oneLine(e.what()) << "\n";
    return 128 + e.signal;
  } catch (const gradel::IoError& e) {
    std::cerr << "gradel: " << oneLine(e.what()) << " (nothing written)\n";
    return kExitIo;
  } catch (const fs::filesystem_error& e) {
    std::cerr << "gradel: " << oneLine(e.what()) << " (nothing written)\n";
    return kExitIo;
  } catch (const std::exception& e) {
    std::cerr << "gradel: internal error: " << oneLine(e.what()) << "\n";
    return kExitInternal;
  } catch (...) {
    std::cerr << "gradel: internal error: unknown exception\n";
    return kExitInternal;
  }
}
