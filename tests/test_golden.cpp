// Golden regression: the state hash (World::stateHash, every position and velocity bit) of a few
// shipped scenes after 50 steps at 1 thread, against tests/golden/state_hashes.json. Any change
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

const char* const kGoldenScenes[] = {"strike", "grasp-two", "drop", "strike-2d", "paper-table1"};
constexpr int kGoldenSteps = 50;

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

std::string hashOf(const std::string& name) {
  Scene scene = loadScene(std::string(GRADEL_SOURCE_DIR) + "/scenes/" + name + ".json");
  scene.simulation.threads = 1;
  BuiltScene built = buildScene(scene);
  for (int i = 0; i < kGoldenSteps; ++i) built.world->step();
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
    for (const char* name : kGoldenScenes) table[name] = hashOf(name);
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
  for (const char* name : kGoldenScenes) {
    ASSERT_TRUE(table.contains(name)) << name << " missing from " << goldenPath() << " [" << key << "]";
    EXPECT_EQ(hashOf(name), table[name].get<std::string>())
        << "scene " << name << ", " << kGoldenSteps << " steps, 1 thread, flavour " << key
        << ": the step's arithmetic changed. If that is intended, run GRADEL_UPDATE_GOLDEN=1 gradel_tests "
           "--gtest_filter='Golden*' and give the reason in the commit (tests/golden/README.md).";
  }
}

}  // namespace
}  // namespace gradel
