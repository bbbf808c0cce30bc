// settings_check.h and the core's own input errors: one check per settings type, in the core's
// words (field names such as `density`), never a CLI flag (`--size`) or a scene key path
// (`simulation.dt`) that a C++ or Python caller never wrote; the scene reader adds those.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "gradel/settings_check.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {
std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(SettingsCheck, CoreErrorsNameTheFieldInTheCoresWords) {
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  SimulationSettings sim;
  sim.dt = -1;
  MaterialSettings material;
  material.density = 0;
  ManipulatorSettings manipulator;
  manipulator.restitution = 2;
  DomainSettings domain;
  domain.enabled = true;
  domain.max = domain.min;
  const std::pair<std::string, std::function<void()>> cases[] = {
      {"dt", [&] { validate(sim); }},
      {"density", [&] { validate(material); }},
      {"restitution", [&] { validate(manipulator); }},
      {"max", [&] { validate(domain, 3); }},
      {"size", [] { presetShape("box", 0, 3); }},
      {"dim", [] { presetShape("box", 4, 5); }},
      {"shape", [] { presetShape("cylinder", 4, 2); }},
      {"density", [&] { makeBody("box", 4, 3, LayoutKind::Gradational, material); }},  // buildRestModel
      {"origin", [&] { makeBody("box", 4, 3, LayoutKind::Gradational, {}, 0.01, Vec3(nan, 0, 0)); }},
  };
  for (const auto& [field, f] : cases) {
    const std::string e = errorOf(f);
    EXPECT_EQ(e.rfind(field + ":", 0), 0u) << "expected \"" << field << ": ...\", got \"" << e << "\"";
    EXPECT_EQ(e.find("--"), std::string::npos) << e;
    for (const char* path : {"simulation.", "material.", "body.", "domain."})
      EXPECT_EQ(e.find(path), std::string::npos) << e;
  }
}
