// gradel-bench: the speed of the paper's Table 1 setting (sec. 3.4) for spheres and cubes of
// several sizes, each layout, at several thread counts. Prints CSV on stdout (one row per
// configuration, medians of --reps repetitions) and progress on stderr.
//
//   gradel-bench [--shapes sphere,box] [--sizes 12,32,64,128,256] [--layouts gradational,uniform,voxel]
//                [--threads 1,2] [--reps 5] [--min-time 0.2] [--max-pairs 40000000] [--find-realtime]
//
// Columns: ns_per_vertex_step = wall time per step / unique vertices; ns_per_pair_step the same
// per element-vertex pair; real_time_factor = simulated seconds per wall second with dt = 1/10 of
// the smallest element's period (the paper's setting: k = 10000, one voxel's mass per vertex);
// bytes_per_vertex = every array of the model, state and scratch / unique vertices;
// state_hash = hash of positions and velocities after exactly 20 steps (identical at any thread
// count, and unchanged by pure speed work).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "gradel/scene_presets.h"

using namespace gradel;
using Clock = std::chrono::steady_clock;

namespace {

struct Row {
  std::string shape, layout;
  int n = 0, threads = 0;
  size_t elements = 0, vertices = 0, pairs = 0;
  double nsPerVertex = 0, nsPerPair = 0, stepsPerSecond = 0, dt = 0, rtf = 0, bytesPerVertex = 0;
  uint64_t hash = 0;
};

template <class T>
std::vector<T> splitList(const std::string& s, T (*conv)(const std::string&)) {
  std::vector<T> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(conv(item));
  return out;
}

Row measure(const std::string& shape, int n, LayoutKind layout, int threads, int reps, double minTime) {
  BuiltScene b = buildScene(paperBenchScene(shape, n, layout, threads));
  b.layout = Layout();  // build inputs are not part of the running simulation's memory
  b.volume = VoxelVolume();
  World& w = *b.world;
  preparePaperBench(w);
  for (int i = 0; i < 20; ++i) w.step();
  Row r;
  r.shape = shape, r.layout = layoutKindName(layout), r.n = n, r.threads = threads;
  r.hash = w.stateHash();
  r.elements = w.model().numElements(), r.vertices = w.model().numVertices(), r.pairs = w.model().numPairs();
  r.dt = w.dt();
  r.bytesPerVertex = double(w.memoryBytes()) / double(r.vertices);
  // Steps per repetition: enough for minTime seconds, from a calibration run.
  int steps = 1;
  for (;;) {
    const auto t0 = Clock::now();
    for (int i = 0; i < steps; ++i) w.step();
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
    for (int i = 0; i < steps; ++i) w.step();
    perStep.push_back(std::chrono::duration<double>(Clock::now() - t0).count() / steps);
  }
  std::sort(perStep.begin(), perStep.end());
  const double t = perStep[perStep.size() / 2];
  r.nsPerVertex = t * 1e9 / double(r.vertices);
  r.nsPerPair = t * 1e9 / double(r.pairs);
  r.stepsPerSecond = 1.0 / t;
  r.rtf = r.dt * r.stepsPerSecond;
  return r;
}

void printHeader() {
  std::printf("shape,n,layout,threads,elements,unique_vertices,pairs,ns_per_vertex_step,ns_per_pair_step,"
              "steps_per_second,dt_s,real_time_factor,bytes_per_vertex,state_hash\n");
}

void printRow(const Row& r) {
  std::printf("%s,%d,%s,%d,%zu,%zu,%zu,%.3f,%.3f,%.1f,%.6g,%.4g,%.1f,%016llx\n", r.shape.c_str(), r.n, r.layout.c_str(),
              r.threads, r.elements, r.vertices, r.pairs, r.nsPerVertex, r.nsPerPair, r.stepsPerSecond, r.dt, r.rtf,
              r.bytesPerVertex, static_cast<unsigned long long>(r.hash));
  std::fflush(stdout);
}

// Largest gradational sphere that runs in real time (real_time_factor >= 1) at `threads`: the
// real-time factor falls monotonically with n, so double n from 32 until it drops below 1, then
// bisect the bracket down to 2 voxels.
void findRealtime(int threads, int reps, double minTime) {
  Row best;
  auto ok = [&](int n) {
    const Row r = measure("sphere", n, LayoutKind::Gradational, threads, reps, minTime);
    std::fprintf(stderr, "  sphere %d: %zu elements, %zu vertices, real-time factor %.3f\n", n, r.elements,
                 r.vertices, r.rtf);
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
  std::printf("# largest real-time gradational sphere at %d threads: n = %d, %zu elements, %zu unique vertices, "
              "real-time factor %.3f (n = %d is not real time)\n",
              threads, best.n, best.elements, best.vertices, best.rtf, hi);
  printRow(best);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"gradel-bench: speed of the paper's Table 1 setting, CSV on stdout"};
  std::string shapes = "sphere,box", sizes = "12,32,64,128,256", layouts = "gradational,uniform,voxel", threads = "1,2";
  int reps = 5;
  double minTime = 0.2, maxPairs = 4.0e7;
  bool findRt = false;
  app.add_option("--shapes", shapes, "Comma-separated: sphere, box");
  app.add_option("--sizes", sizes, "Comma-separated grid sizes n (voxels)");
  app.add_option("--layouts", layouts, "Comma-separated: gradational, uniform, voxel");
  app.add_option("--threads", threads, "Comma-separated thread counts");
  app.add_option("--reps", reps, "Repetitions (the median is reported)")->check(CLI::Range(1, 1000));
  app.add_option("--min-time", minTime, "Seconds per repetition")->check(CLI::Range(0.001, 100.0));
  app.add_option("--max-pairs", maxPairs, "Skip configurations with more element-vertex pairs (memory)");
  app.add_flag("--find-realtime", findRt, "Also search the largest real-time gradational sphere at the largest thread count");
  CLI11_PARSE(app, argc, argv);
  try {
    const auto shapeList = splitList<std::string>(shapes, [](const std::string& s) { return s; });
    const auto sizeList = splitList<int>(sizes, [](const std::string& s) { return std::stoi(s); });
    const auto layoutList = splitList<LayoutKind>(layouts, [](const std::string& s) { return parseLayoutKind(s); });
    const auto threadList = splitList<int>(threads, [](const std::string& s) { return std::stoi(s); });
    printHeader();
    for (const std::string& shape : shapeList)
      for (int n : sizeList)
        for (LayoutKind layout : layoutList) {
          // Pair count estimate from the voxel count, to skip what would not fit in memory.
          const double voxels = double(n) * n * n * (shape == "sphere" ? 0.5236 : 1.0);
          const double pairs = layout == LayoutKind::Voxel ? 8 * voxels : layout == LayoutKind::Uniform ? voxels : 0;
          if (pairs > maxPairs) {
            std::printf("# skipped %s %d %s: ~%.0f pairs > --max-pairs\n", shape.c_str(), n, layoutKindName(layout), pairs);
            continue;
          }
          for (int t : threadList) {
            std::fprintf(stderr, "%s %d %s threads %d\n", shape.c_str(), n, layoutKindName(layout), t);
            printRow(measure(shape, n, layout, t, reps, minTime));
          }
        }
    if (findRt) findRealtime(*std::max_element(threadList.begin(), threadList.end()), reps, minTime);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gradel-bench: %s\n", e.what());
    return 2;
  }
  return 0;
}
