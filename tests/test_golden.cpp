// Golden regression: the state hash (World::stateHash, every position and velocity bit) of a few
// shipped scenes after a few steps at 1 thread (50 unless the case says otherwise), against
// tests/golden/state_hashes.json. The cases cover every integrator path of World::step: the
// explicit vertex pass with manipulators, walls and pins (strike, grasp-two, drop, strike-2d,
// paper-table1, box-realtime's 17k-vertex body), body contacts after each integrator (two-balls
// symplectic, implicit and large step; the stack, explicit and large step). Any change
// to the arithmetic of a step changes these hashes; the test makes that visible, and updating
// the file is a deliberate act with its reason in the commit (tests/golden/README.md):
//   GRADEL_UPDATE_GOLDEN=1 build/gradel_tests --gtest_filter='Golden*'
// The hashes are per build flavour (compiler and instruction set: with FMA the compiler may
// contract a * b + c, which changes the last bits); a flavour not in the file is skipped with a
// message naming the command that records it.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "gradel/scene.h"

namespace gradel {
namespace {

constexpr int kGoldenSteps = 50;

struct GoldenCase {
  const char* key;    ///< Its name in state_hashes.json: the scene, and "/integrator" when overridden.
  const char* scene;  ///< scenes/<scene>.json
  const char* integrator;  ///< nullptr: the scene's own.
  int steps;
};
// Frame-size integrators run at 1/60 s: a few steps reach the contacts. box-realtime is 17k
// vertices: 5 steps keep the test fast.
const GoldenCase kGoldenCases[] = {
    {"strike", "strike", nullptr, kGoldenSteps},
    {"grasp-two", "grasp-two", nullptr, kGoldenSteps},
    {"drop", "drop", nullptr, kGoldenSteps},
    {"strike-2d", "strike-2d", nullptr, kGoldenSteps},
    {"paper-table1", "paper-table1", nullptr, kGoldenSteps},
    {"two-balls/symplectic", "two-balls", "symplectic", 100},
    {"two-balls/implicit", "two-balls", "implicit", 12},
    {"two-balls/large_step", "two-balls", "large_step", 12},
    {"stack", "stack", nullptr, 300},
    {"stack/large_step", "stack", "large_step", 20},
    {"box-realtime", "box-realtime", nullptr, 5},
};

std::string goldenPath() { return std::string(GRADEL_SOURCE_DIR) + "/tests/golden/state_hashes.json"; }

std::string flavour() {
#if defined(__clang__)
  std::string f = "clang-" + std::to_string(__clang_major__);
#elif defined(__GNUC__)
  std::string f = "gcc-" + std::to_string(__GNUC__);
#else
  std::string f = "other";
#endif
#if defined(__AVX2__) && defined(__FMA__)
  return f + "/x86-64-v3";
#else
  return f + "/generic";
#endif
}

std::string hashOf(const GoldenCase& c) {
  Scene scene = loadScene(std::string(GRADEL_SOURCE_DIR) + "/scenes/" + c.scene + ".json");
  scene.simulation.threads = 1;
  if (c.integrator) scene.simulation.integrator = parseIntegratorKind(c.integrator);
  BuiltScene built = buildScene(scene);
  for (int i = 0; i < c.steps; ++i) built.world->step();
  char text[19];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(built.world->stateHash()));
  return text;
}

nlohmann::json readGolden() {
  std::ifstream in(goldenPath());
  if (!in) return nlohmann::json::object();
  return nlohmann::json::parse(in);
}

TEST(Golden, StateHashesOfShortScenes) {
  const bool update = std::getenv("GRADEL_UPDATE_GOLDEN") && std::string(std::getenv("GRADEL_UPDATE_GOLDEN")) == "1";
  nlohmann::json golden = readGolden();
  const std::string key = flavour();
  if (update) {
    nlohmann::json& table = golden["hashes"][key];
    for (const GoldenCase& c : kGoldenCases) {
      table[c.key] = hashOf(c);
      if (c.steps != kGoldenSteps) golden["case_steps"][c.key] = c.steps;
    }
    golden["steps"] = kGoldenSteps;
    golden["threads"] = 1;
    const std::string tmp = goldenPath() + ".tmp";
    std::ofstream(tmp) << golden.dump(2) << "\n";
    std::filesystem::rename(tmp, goldenPath());
    std::printf("updated %s for %s: commit it with the reason the hashes changed\n", goldenPath().c_str(), key.c_str());
    return;
  }
  ASSERT_EQ(golden.value("steps", 0), kGoldenSteps) << goldenPath();
  if (!golden.contains("hashes") || !golden["hashes"].contains(key))
    GTEST_SKIP() << "no golden hashes for build flavour " << key << " in " << goldenPath()
                 << "; record them with GRADEL_UPDATE_GOLDEN=1 gradel_tests --gtest_filter='Golden*'";
  const nlohmann::json& table = golden["hashes"][key];
  for (const GoldenCase& c : kGoldenCases) {
    const std::string name = c.key;
    ASSERT_TRUE(table.contains(name)) << name << " missing from " << goldenPath() << " [" << key << "]";
    const int recorded = golden.contains("case_steps") ? golden["case_steps"].value(name, kGoldenSteps) : kGoldenSteps;
    ASSERT_EQ(recorded, c.steps) << name << ": recorded at another number of steps (" << goldenPath() << ")";
    EXPECT_EQ(hashOf(c), table[name].get<std::string>())
        << "case " << name << ", " << c.steps << " steps, 1 thread, flavour " << key
        << ": the step's arithmetic changed. If that is intended, run GRADEL_UPDATE_GOLDEN=1 gradel_tests "
           "--gtest_filter='Golden*' and give the reason in the commit (tests/golden/README.md).";
  }
}

}  // namespace
}  // namespace gradel
