// libFuzzer target for scene files (JSON): bytes -> parseScene -> buildScene (volume, layout,
// rest model, world) -> the run's checks (run_budget.h) -> a few steps with the divergence guard
// (divergence.h). An InputError is the expected answer to a bad scene; anything else (a crash, a
// sanitizer report, another exception type, a leak, an allocation past -rss_limit_mb) is a bug.
//
// Limits are lowered so each execution is fast: at most 16^3 voxels and 64 MB (SizeLimits, the
// same checks as at full size), no more than 4 steps. Scenes that read files (body.source, pin
// masks) are parsed but not built: the readers have their own targets (fuzz_reader.cpp), and a
// path in fuzzed bytes could name any file on the machine.
#include <cstdint>
#include <string>

#include "gradel/divergence.h"
#include "gradel/scene.h"
#include "gradel/shared/run_budget.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace gradel;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    Scene scene = parseScene(text, "fuzz.json");
    if (scene.bodies[0].source) return 0;
    for (const PinSettings& p : scene.pins)
      if (p.mask && p.mask->source) return 0;
    scene.simulation.threads = 1;
    SizeLimits limits;
    limits.maxVoxels = 16 * 16 * 16;
    limits.maxBytes = 64u << 20;
    BuiltScene built = buildScene(scene, limits);
    World& world = *built.world;
    const double dt = world.dt();
    checkRunBudget(estimateRun(scene.output.duration, dt, world.model().numVertices(), scene.simulation.integrator), dt,
                   scene.output.duration, std::nullopt);
    DivergenceGuard guard(energyBudget(world, scene.output.duration));
    for (int i = 0; i < 4; ++i) {
      world.step();
      (void)guard.check(world.metrics(), world.contactWork(), "fuzz");
    }
  } catch (const InputError&) {
  }
  return 0;
}
