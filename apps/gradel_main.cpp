// gradel: command-line front end.
//   gradel layout --shape sphere --size 12 [--dim 2|3] [--layout ...] [--json]
//   gradel run SCENE.json [--out DIR] [--duration S] [--threads N]
//   gradel render SCENE.json [--out DIR] [--frames N] [--size WxH] ...   (render_command.h)
//   gradel --version
// Exit codes: 0 ok, 1 internal error, 2 bad input (one line on stderr, nothing written),
// 3 simulation diverged (nothing written), 4 no OpenGL for `render`, 130 interrupted (nothing written).
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "gradel/layout.h"
#include "gradel/output.h"
#include "gradel/scene.h"
#include "gradel/shapes.h"
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
constexpr int kExitInterrupted = 130;  // 128 + SIGINT, as shells report it

struct Diverged : std::runtime_error {
  using std::runtime_error::runtime_error;
};
struct Interrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
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
  const gradel::ShapeSpec spec = gradel::presetShape(o.shape, o.size, o.dim);
  const gradel::VoxelVolume volume = gradel::rasterize(spec);
  const gradel::Layout layout = gradel::buildLayout(volume, kind);
  const gradel::LayoutStats s = gradel::layoutStats(layout, volume);
  // The voxel layout (one element per voxel) is the baseline the paper's savings refer to.
  const gradel::LayoutStats base =
      kind == gradel::LayoutKind::Voxel ? s : gradel::layoutStats(gradel::buildLayout(volume, gradel::LayoutKind::Voxel), volume);

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
  line("shape", o.shape + " " + std::to_string(o.size) + (o.dim == 3 ? "^3" : "^2") + " (" + std::to_string(o.dim) + "D)");
  line("layout", gradel::layoutKindName(kind));
  line("voxels", std::to_string(s.voxels));
  line("elements", withRatio(s.elements, base.elements));
  for (size_t l = 0; l < s.elementsPerLevel.size(); ++l)
    line("  level " + std::to_string(l) + " (edge " + std::to_string(kind == gradel::LayoutKind::Voxel ? 1u : 2u << l) + ")",
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
};

std::atomic<bool> gInterrupted{false};
extern "C" void onSigint(int) { gInterrupted = true; }

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

bool finiteState(const gradel::State& s) {
  for (const gradel::Vec3& p : s.positions)
    if (!p.allFinite()) return false;
  for (const gradel::Vec3& v : s.velocities)
    if (!v.allFinite()) return false;
  return true;
}

std::string hex64(uint64_t h) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
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
  const Real duration = scene.output.duration, interval = scene.output.frameInterval;
  // Frames after t = 0; the last one lands exactly on `duration`.
  const double framesD = std::ceil(duration / interval - 1e-9);
  if (framesD > 1e6)
    throw InputError(o.scene + ": simulation.frame_interval: " + json(interval).dump() + " s gives " +
                     json(framesD).dump() + " frames (expected at most 1000000 frames)");
  const size_t frames = size_t(std::max(1.0, framesD));

  gradel::BuiltScene built;
  try {
    built = gradel::buildScene(scene);
  } catch (const InputError& e) {
    throw InputError(o.scene + ": " + e.what());
  }
  gradel::World& world = *built.world;
  const gradel::RestModel& model = world.model();

  gradel::OutputDirectory dir(o.out.empty() ? fs::path("out") / scene.name : fs::path(o.out), "run.pvd");
  fs::copy_file(o.scene, dir.file("scene.json"));
  gradel::MetricsCsv csv(dir.file("metrics.csv"));
  std::vector<gradel::PvdFrame> pvd;
  Real maxPenetration = 0, maxStress = 0;
  gradel::Metrics last;

  auto writeFrame = [&](size_t index) {
    std::vector<gradel::Real> elementStress;
    const gradel::Metrics m = world.metrics(&elementStress);  // one pass over the elements per frame
    csv.append(m);
    maxPenetration = std::max(maxPenetration, m.maxPenetration);
    maxStress = std::max(maxStress, m.maxStress);
    last = m;
    const std::string name = gradel::frameFileName(index);
    gradel::writeVtu(dir.file(name), model, world.state(), world.vertexStress(elementStress), elementStress);
    pvd.push_back({world.time(), name});
  };

  gInterrupted = false;
  auto previousHandler = std::signal(SIGINT, onSigint);
  struct RestoreHandler {
    decltype(previousHandler) h;
    ~RestoreHandler() { std::signal(SIGINT, h); }
  } restore{previousHandler};

  const Real dt = world.dt();
  // Advance in chunks of a few steps so that divergence, Ctrl-C and the progress bar are
  // noticed within a frame; the sequence of steps is the same as one advanceTo per frame.
  constexpr Real kChunkSteps = 32;
  Progress progress;
  const auto wallStart = std::chrono::steady_clock::now();
  writeFrame(0);
  for (size_t f = 1; f <= frames; ++f) {
    const Real tFrame = std::min(Real(f) * interval, duration);
    while (world.time() < tFrame - 0.5 * dt) {
      const Real before = world.time();
      world.advanceTo(std::min(tFrame, before + kChunkSteps * dt));
      if (world.time() == before) world.step();  // never spin without progress
      if (!finiteState(world.state())) {
        char msg[160];
        std::snprintf(msg, sizeof msg, "simulation diverged at t=%.6g s (dt = %.3g s), try a smaller dt", world.time(), dt);
        throw Diverged(msg);
      }
      if (gInterrupted) throw Interrupted("interrupted; nothing written");
      progress.update(world.time() / duration);
    }
    writeFrame(f);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wallStart).count();
  csv.close();
  gradel::writePvd(dir.file("run.pvd"), pvd);
  dir.commit();

  json j;
  j["scene"] = scene.name;
  j["steps"] = std::llround(world.time() / dt);
  j["dt"] = dt;
  j["simulated_seconds"] = world.time();
  j["frames"] = pvd.size();
  j["wall_seconds"] = wall;
  j["real_time_factor"] = wall > 0 ? world.time() / wall : 0.0;
  j["elements"] = model.numElements();
  j["vertices"] = model.numVertices();
  j["pairs"] = model.numPairs();
  j["final_kinetic_energy"] = last.kineticEnergy;
  j["max_penetration"] = maxPenetration;
  j["max_stress"] = maxStress;
  j["state_hash"] = hex64(world.stateHash());
  j["out"] = dir.target().string();
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"gradel: gradational elastic elements from voxel volumes (Miyazaki et al. 2002)", "gradel"};
  app.set_version_flag("--version", std::string("gradel ") + GRADEL_VERSION);
  app.require_subcommand(1);

  LayoutOptions lo;
  CLI::App* layout = app.add_subcommand("layout", "Build an element layout from a preset shape and print its counts");
  layout->add_option("--shape", lo.shape, "box | sphere | cylinder (3D only)")->capture_default_str();
  layout->add_option("--size", lo.size, "Grid edge [voxels]; the shape is inscribed in size^dim voxels")->capture_default_str();
  layout->add_option("--dim", lo.dim, "2 or 3")->capture_default_str();
  layout->add_option("--layout", lo.layout, "gradational | uniform | voxel")->capture_default_str();
  layout->add_flag("--json", lo.json, "Print one JSON object instead of text");

  RunOptions ro;
  CLI::App* run = app.add_subcommand("run", "Simulate a scene file and write frames, metrics and a JSON summary");
  run->add_option("scene", ro.scene, "Scene file (JSON, see docs/scenes.md)")->required();
  run->add_option("--out", ro.out, "Result directory (default: out/<scene name>)");
  run->add_option("--duration", ro.duration, "Simulated time [s] (overrides simulation.duration)");
  run->add_option("--threads", ro.threads, "Worker threads (overrides simulation.threads)");

#ifdef GRADEL_WITH_RENDER
  gradel::render::RenderCommandOptions rendo;
  CLI::App* render = gradel::render::addRenderCommand(app, rendo);
#endif

  try {
    app.parse(argc, argv);
    if (layout->parsed()) return runLayout(lo);
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
    return kExitInterrupted;
  } catch (const std::exception& e) {
    std::cerr << "gradel: internal error: " << oneLine(e.what()) << "\n";
    return kExitInternal;
  } catch (...) {
    std::cerr << "gradel: internal error: unknown exception\n";
    return kExitInternal;
  }
}
