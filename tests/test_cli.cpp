// Tests for the command-line program (apps/gradel_main.cpp), run as a separate process:
// bad input gives exit code 2, one line on stderr naming the file and field, and writes
// nothing; `layout --json` prints parseable counts; `run` writes a complete result or none.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <set>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

namespace {
namespace fs = std::filesystem;
using nlohmann::json;

struct Result {
  int code = -1;
  std::string out, err;
};

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("gradel-cli-test-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs `gradel ARGS` in dir_, capturing stdout, stderr and the exit code.
  Result run(const std::string& args, const std::string& env = "") {
    const std::string cmd = "cd '" + dir_.string() + "' && " + env + " '" + std::string(GRADEL_CLI_PATH) + "' " + args +
                            " > stdout.txt 2> stderr.txt";
    const int status = std::system(cmd.c_str());
    Result r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    r.out = readFile(dir_ / "stdout.txt");
    r.err = readFile(dir_ / "stderr.txt");
    fs::remove(dir_ / "stdout.txt");
    fs::remove(dir_ / "stderr.txt");
    return r;
  }
  void write(const std::string& name, const std::string& text) { std::ofstream(dir_ / name) << text; }

  // A bad scene: exit 2, one stderr line "gradel: FILE: ...FIELD...", no output directory.
  void expectRejected(const std::string& name, const std::string& text, const std::string& field) {
    SCOPED_TRACE(name + ": " + text);
    write(name, text);
    const Result r = run("run " + name + " --out result");
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(r.err.rfind("gradel: " + name + ": ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(field), std::string::npos) << r.err;
    ASSERT_FALSE(r.err.empty());
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "not one line: " << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_FALSE(fs::exists(dir_ / "result"));
    for (const auto& e : fs::directory_iterator(dir_))
      EXPECT_EQ(e.path().filename().string().find("result"), std::string::npos) << "left behind: " << e.path();
  }

  fs::path dir_;
};

// A small, quick scene (a 4^3 ball, a few hundred steps) for runs that must succeed.
const char* kTinyScene = R"({
  "body": {"shape": "sphere", "size": 4, "voxel_size": 0.01},
  "simulation": {"gravity": [0, -9.81, 0], "duration": 0.02, "frame_interval": 0.01},
  "domain": {"min": [-0.1, 0.0, -0.1], "max": [0.1, 0.2, 0.1]}
})";

TEST_F(CliTest, RunBadSceneFilesExit2OneLineNothingWritten) {
  expectRejected("unknown.json", R"({"body": {"shape": "sphere", "size": 4, "radiuss": 3}})", "body.radiuss");
  expectRejected("nested.json",
                 R"({"body": {"shape": "sphere", "size": 4}, "manipulators": [{"type": "sphere", "raduis": 1}]})",
                 "manipulators[0].raduis");
  expectRejected("malformed.json", "{\"body\": {\"shape\": \"sphere\",\n \"size\": 4,}}",
                 "invalid JSON: parse error at line 2");
  expectRejected("missing.json", R"({"body": {"size": 4}})", "body.shape");
  expectRejected("range.json", R"({"body": {"shape": "sphere", "size": 4, "voxel_size": -1}})", "body.voxel_size");
  expectRejected("enum.json", R"({"body": {"shape": "sphere", "size": 4}, "simulation": {"integrator": "rk4"}})",
                 "simulation.integrator");
  expectRejected("dim.json",
                 R"({"dim": 2, "body": {"shape": "sphere", "size": 4}, "manipulators": [{"type": "cylinder"}]})",
                 "manipulators[0].type");
  expectRejected("blade.json", R"({"body": {"shape": "box", "size": 4}, "manipulators": [{"type": "blade",
      "axes": ["x", [1, 1, 0]], "half_extents": [0.05, 0.02]}]})",
                 "manipulators[0].axes");
  expectRejected("blade-size.json", R"({"body": {"shape": "box", "size": 4}, "manipulators": [{"type": "blade",
      "axes": ["x", "y"], "half_extents": [0.05]}]})",
                 "manipulators[0].half_extents");
  // Valid JSON and schema, but an empty shape: caught when the body is built, still named.
  expectRejected("empty.json", R"({"body": {"shape": "union", "grid": [4, 4, 4],
      "primitives": [{"type": "sphere", "center": [40, 40, 40], "radius": 1}]}})",
                 "empty");
}

TEST_F(CliTest, RunMissingFileExit2) {
  const Result r = run("run nope.json --out result");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "gradel: nope.json: cannot read: No such file or directory\n");
  EXPECT_FALSE(fs::exists(dir_ / "result"));
}

TEST_F(CliTest, BadArgumentsExit2OneLine) {
  for (const std::string args : {"", "frobnicate", "layout --size abc", "layout --shape cube", "run",
                                 "run x.json --threads 0", "layout --dim 5", "run x.json --duration -1"}) {
    SCOPED_TRACE(args);
    write("x.json", kTinyScene);
    const Result r = run(args);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(r.err.rfind("gradel: ", 0), 0u) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(CliTest, UnknownSubcommandIsNamed) {
  const Result r = run("frobnicate x.json");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err.rfind("gradel: unknown subcommand 'frobnicate' (expected one of layout, run, study", 0), 0u) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
}

// A mesh or volume file that is missing: the message shows where it was looked for, resolved
// against the scene's folder and the working directory (an absolute path).
TEST_F(CliTest, MissingSourceFileShowsTheResolvedPath) {
  fs::create_directories(dir_ / "sub");
  write("sub/s.json", R"({"body": {"source": {"file": "../meshes/nope.obj"}}})");
  const Result r = run("run sub/s.json --out res");
  EXPECT_EQ(r.code, 2);
  const std::string resolved = (fs::weakly_canonical(dir_) / "meshes" / "nope.obj").string();
  EXPECT_NE(r.err.find("sub/s.json: body.source.file: \"../meshes/nope.obj\" is not a readable file (looked for " +
                       resolved + ")"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "res"));
}

#ifdef GRADEL_WITH_RENDER
// `render --section` shows the section: no surface drawn over it unless --surface asks for one.
TEST_F(CliTest, RenderSectionDrawsNoSurfaceByDefault) {
  write("x.json", kTinyScene);
  Result r = run("render x.json --wireframe --section --frames 1 --no-pictures --export obj --no-video --out a");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(json::parse(readFile(dir_ / "a" / "render.json")).at("surface"), "none");
  r = run("render x.json --wireframe --section --surface smooth --frames 1 --no-pictures --export obj --no-video --out b");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(json::parse(readFile(dir_ / "b" / "render.json")).at("surface"), "smooth");
  r = run("render x.json --wireframe --frames 1 --no-pictures --export obj --no-video --out c");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(json::parse(readFile(dir_ / "c" / "render.json")).at("surface"), "smooth");
}
#endif

TEST_F(CliTest, VersionPrintsVersion) {
  const Result r = run("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.out.rfind("gradel ", 0), 0u) << r.out;
}

TEST_F(CliTest, LayoutJsonHasFewerPairsThanVoxelLayout) {
  const Result r = run("layout --shape sphere --size 12 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_GT(j.at("elements").get<int>(), 0);
  EXPECT_EQ(j.at("voxels").get<int>(), j.at("voxel_layout").at("elements").get<int>());
  EXPECT_LT(j.at("pairs").get<int>(), j.at("voxel_layout").at("pairs").get<int>());
  EXPECT_LT(j.at("unique_vertices").get<int>(), j.at("voxel_layout").at("unique_vertices").get<int>());
  int perLevel = 0;
  for (const auto& n : j.at("elements_per_level")) perLevel += n.get<int>();
  EXPECT_EQ(perLevel, j.at("elements").get<int>());
}

TEST_F(CliTest, LayoutTextIsAlignedTable) {
  const Result r = run("layout --shape box --size 8 --dim 2 --layout uniform");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("elements"), std::string::npos);
  EXPECT_NE(r.out.find("element-vertex pairs"), std::string::npos);
  EXPECT_NE(r.out.find("hanging vertices"), std::string::npos);
}

TEST_F(CliTest, RunWritesCompleteResultAndSummary) {
  write("tiny.json", kTinyScene);
  const Result r = run("run tiny.json --out res --threads 1");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;  // no progress bar when stderr is not a terminal
  const json j = json::parse(r.out);
  for (const char* key : {"scene", "steps", "dt", "wall_seconds", "real_time_factor", "elements", "vertices", "pairs",
                          "final_kinetic_energy", "max_penetration", "max_stress", "max_strain", "out"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j.at("scene"), "tiny");
  EXPECT_EQ(j.at("out"), "res");
  EXPECT_GT(j.at("steps").get<int>(), 0);

  const fs::path res = dir_ / "res";
  EXPECT_EQ(readFile(res / "scene.json"), kTinyScene);
  EXPECT_TRUE(fs::exists(res / "run.pvd"));
  EXPECT_TRUE(fs::exists(res / "frame_00000.vtu"));
  EXPECT_TRUE(fs::exists(res / "frame_00002.vtu"));
  EXPECT_FALSE(fs::exists(res / "frame_00003.vtu"));
  std::istringstream csv(readFile(res / "metrics.csv"));
  int lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  EXPECT_EQ(lines, 1 + 3);  // header + frames at t = 0, 0.01, 0.02
  EXPECT_NE(readFile(res / "run.pvd").find("frame_00002.vtu"), std::string::npos);

  // Runs are deterministic, and a second run replaces the first as a whole.
  const Result again = run("run tiny.json --out res --duration 0.01");
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_FALSE(fs::exists(res / "frame_00002.vtu"));
  // Half the duration, half the steps: each run ends at the step nearest its duration, so the two
  // roundings can differ by one step (the operator rule's dt does not divide 0.01 s).
  EXPECT_LE(std::abs(json::parse(again.out).at("steps").get<int>() * 2 - j.at("steps").get<int>()), 1);
  EXPECT_EQ(j.at("dt_rule").get<std::string>().rfind("operator x 0.175: ", 0), 0u) << j.at("dt_rule");  // where dt came from
}

// metrics.csv carries the frame-averaged contact forces: per manipulator and the walls. A ball
// resting on the floor with a sphere parked on top of it: the floor carries the ball's weight
// and the sphere's push, the sphere is pushed up.
TEST_F(CliTest, RunMetricsHaveContactForceColumns) {
  write("press.json", R"({
  "body": {"shape": "sphere", "size": 4, "voxel_size": 0.01},
  "simulation": {"gravity": [0, -9.81, 0], "duration": 0.02, "frame_interval": 0.01, "damping": 10},
  "domain": {"min": [-0.1, 0.0, -0.1], "max": [0.1, 0.2, 0.1], "restitution": 0},
  "manipulators": [{"type": "sphere", "radius": 0.02, "restitution": 0,
                    "path": [{"t": 0, "position": [0.02, 0.059, 0.02]}]}]
})");
  const Result r = run("run press.json --out res");
  ASSERT_EQ(r.code, 0) << r.err;
  std::istringstream csv(readFile(dir_ / "res" / "metrics.csv"));
  std::string header, line, last;
  std::getline(csv, header);
  while (std::getline(csv, line)) last = line;
  std::vector<std::string> names, cells;
  for (std::istringstream h(header); std::getline(h, line, ',');) names.push_back(line);
  for (std::istringstream c(last); std::getline(c, line, ',');) cells.push_back(line);
  ASSERT_EQ(names.size(), 14u + 12u + 36u + 1u);
  EXPECT_EQ(names.back(), "max_strain");
  ASSERT_EQ(cells.size(), names.size());
  EXPECT_EQ(names[14], "m0_fx");
  EXPECT_EQ(names[19], "m0_tz");
  EXPECT_EQ(names[20], "wall_fx");
  EXPECT_EQ(names[25], "wall_tz");
  EXPECT_GT(std::stod(cells[15]), 0) << last;  // m0_fy: the ball pushes the sphere up
  EXPECT_LT(std::stod(cells[21]), 0) << last;  // wall_fy: and the floor down
  // Per wall (xmin, xmax, ymin, ...): the floor ymin carries all of it, the other walls nothing.
  EXPECT_EQ(names[26], "wall_xmin_fx");
  EXPECT_EQ(names[39], "wall_ymin_fy");
  EXPECT_EQ(names[61], "wall_zmax_tz");
  EXPECT_EQ(cells[39], cells[21]) << last;
  for (size_t c = 26; c < names.size(); ++c)
    if (names[c].rfind("wall_", 0) == 0 && names[c].rfind("wall_ymin_", 0) != 0) {
      EXPECT_EQ(std::stod(cells[c]), 0) << names[c];
    }
}

// A carving run (docs/carving.md, "Feedback"): metrics.csv ends with the removed material since
// t = 0 (voxels, volume, mass; h = 2^-7 m so that n h^3 and rho h^3 are exact), its last row is
// the summary's totals, the rows never decrease; the summary counts the events and their cost.
TEST_F(CliTest, CarvingRunReportsRemovedMaterialAndEvents) {
  write("drill.json", R"({
  "body": {"shape": "box", "size": 8, "voxel_size": 0.0078125},
  "material": {"density": 1000},
  "simulation": {"gravity": [0, 0, 0], "duration": 0.1, "frame_interval": 0.02},
  "domain": {"min": [-0.1, 0.0, -0.1], "max": [0.2, 0.2, 0.2], "restitution": 0},
  "manipulators": [{"type": "sphere", "radius": 0.015, "restitution": 0, "carve": true,
                    "path": [{"t": 0, "position": [0.03125, 0.085, 0.03125]},
                             {"t": 0.1, "position": [0.03125, 0.02, 0.03125]}]}]
})");
  const Result r = run("run drill.json --out res --threads 1");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  for (const char* key : {"carve_events", "carve_body_events", "carved_voxels", "carved_volume", "carved_mass",
                          "carve_seconds", "carve_event_seconds", "carve_event_max_seconds"})
    ASSERT_TRUE(j.contains(key)) << key;
  const size_t voxels = j.at("carved_voxels").get<size_t>();
  const double h3 = 0.0078125 * 0.0078125 * 0.0078125;
  EXPECT_GT(voxels, 20u);
  EXPECT_GE(j.at("carve_events").get<size_t>(), 2u);
  EXPECT_EQ(j.at("carve_body_events"), j.at("carve_events"));  // one body, one tool
  EXPECT_EQ(j.at("carved_volume").get<double>(), double(voxels) * h3);
  EXPECT_EQ(j.at("carved_mass").get<double>(), double(voxels) * 1000 * h3);
  EXPECT_LE(j.at("carve_event_max_seconds").get<double>(), j.at("carve_event_seconds").get<double>());
  EXPECT_LE(j.at("carve_event_seconds").get<double>(), j.at("carve_seconds").get<double>());
  EXPECT_GT(j.at("carve_event_max_seconds").get<double>(), 0);
  // dt = auto follows each carved body (the operator rule estimated again): the steps counted at
  // each chunk's dt (which may be shorter in between than at either end), not the first one's;
  // the rule says where dt came from.
  const double dt0 = j.at("dt").get<double>(), dt1 = j.at("final_dt").get<double>();
  EXPECT_GE(j.at("steps").get<double>(), 0.1 / std::max(dt0, dt1) - 1);
  EXPECT_NE(j.at("dt_rule").get<std::string>().find("(estimated again after carving)"), std::string::npos)
      << j.at("dt_rule");

  std::istringstream csv(readFile(dir_ / "res" / "metrics.csv"));
  std::string header, line;
  std::getline(csv, header);
  std::vector<std::string> names;
  for (std::istringstream h(header); std::getline(h, line, ',');) names.push_back(line);
  ASSERT_EQ(names.size(), 14u + 6u + 6u + 36u + 1u + 3u);
  EXPECT_EQ(names[62], "max_strain");  // the columns before the carving ones kept their places
  EXPECT_EQ(names[63], "removed_voxels");
  EXPECT_EQ(names[64], "removed_volume");
  EXPECT_EQ(names[65], "removed_mass");
  double before = 0;
  std::vector<std::string> cells;
  int rows = 0;
  while (std::getline(csv, line)) {
    cells.clear();
    for (std::istringstream c(line); std::getline(c, line, ',');) cells.push_back(line);
    ASSERT_EQ(cells.size(), names.size());
    EXPECT_GE(std::stod(cells[63]), before);
    before = std::stod(cells[63]);
    EXPECT_EQ(std::stod(cells[64]), std::stod(cells[63]) * h3);
    ++rows;
  }
  EXPECT_EQ(rows, 6);
  EXPECT_NEAR(std::stod(cells[0]), 0.1, 1e-3);  // the last frame, at the step nearest the duration
  EXPECT_EQ(std::stod(cells[63]), double(voxels));
  EXPECT_EQ(std::stod(cells[64]), j.at("carved_volume").get<double>());
  EXPECT_EQ(std::stod(cells[65]), j.at("carved_mass").get<double>());
}

TEST_F(CliTest, RunDefaultOutIsOutSlashSceneName) {
  write("tiny.json", R"({"name": "named", "body": {"shape": "box", "size": 2}, "simulation": {"duration": 0.001}})");
  const Result r = run("run tiny.json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "out" / "named" / "run.pvd"));
}

TEST_F(CliTest, RunForeignOutDirectoryIsRefused) {
  write("tiny.json", kTinyScene);
  fs::create_directories(dir_ / "docs");
  std::ofstream(dir_ / "docs" / "thesis.tex") << "keep me";
  const Result r = run("run tiny.json --out docs");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("refusing"), std::string::npos) << r.err;
  EXPECT_EQ(readFile(dir_ / "docs" / "thesis.tex"), "keep me");
}

TEST_F(CliTest, RunDivergenceExit3NothingWritten) {
  // dt far above the stability limit (the smallest period here is ~2 ms): the state blows up
  // to inf/NaN within a few hundred steps.
  write("unstable.json", R"({"body": {"shape": "sphere", "size": 6, "velocity": [0, 0, 1]},
      "simulation": {"dt": 0.05, "gravity": [0, 0, 0], "duration": 100, "frame_interval": 10},
      "manipulators": [{"type": "sphere", "radius": 0.02, "path": [{"t": 0, "position": [0.03, 0.03, 0.1]}]}]})");
  const Result r = run("run unstable.json --out res");
  EXPECT_EQ(r.code, 3) << r.err << r.out;
  EXPECT_NE(r.err.find("simulation diverged at t="), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("simulation.dt = 0.05 s"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("stability limit"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());
  EXPECT_FALSE(fs::exists(dir_ / "res"));
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find("res"), std::string::npos) << "left behind: " << e.path();
}

// ---- issue 15: limits, frames, I/O errors, signals, divergence --------------------------------

TEST_F(CliTest, LayoutSizeLimitsNameTheKeyAndEstimate) {
  Result r = run("layout --shape sphere --size 1588");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("gradel: --size: a grid of 1588 x 1588 x 1588 = 4004529472 voxels is over the limit", 0), 0u)
      << r.err;
  r = run("layout --shape sphere --size 4097");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--size"), std::string::npos) << r.err;
  // The memory estimate, before the layout is built (a low limit stands in for a small machine).
  r = run("layout --shape box --size 96 --layout voxel", "GRADEL_MEMORY_LIMIT_MB=50");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("gradel: --size: the voxel layout of this body has 884736 elements", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("over the memory limit of 52.4 MB"), std::string::npos) << r.err;
  // The voxel baseline of a gradational layout is counted, not built: it fits the same limit.
  r = run("layout --shape box --size 96 --json", "GRADEL_MEMORY_LIMIT_MB=50");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j.at("voxel_layout").at("elements").get<int>(), 96 * 96 * 96);
  EXPECT_EQ(j.at("voxel_layout").at("unique_vertices").get<int>(), 97 * 97 * 97);
  EXPECT_EQ(j.at("voxel_layout").at("pairs").get<int>(), 8 * 96 * 96 * 96);
}

// A body too big for the run's vertex-step budget is refused from the layout's counts, before
// the layout or model is built, naming the key and the limit (issue 28: body.size 1000 took 42 s
// and 3.3 GB before the refusal).
TEST_F(CliTest, RunBodyTooBigForTheRunRefusedBeforeBuildingNamingTheKey) {
  // 31007 vertices; 4000 s are at least 7.3e6 steps of the voxel probe's dt (5.5e-4 s at the
  // operator rule; 3000 s, at least 9.5e6 steps of the vertex rule's 3.1e-4 s, were refused
  // early before and pass the probe at the larger dt).
  write("big.json", R"({"body": {"shape": "sphere", "size": 64},
      "simulation": {"duration": 4000, "frame_interval": 100}})");
  Result r = run("run big.json --out res");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("gradel: big.json: body.size: the gradational layout of this body has ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("vertices, over the limit of "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("that a run of 4000 s allows (dt at most about"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--max-steps"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "res"));
  // The same body for a short run is fine.
  write("short.json", R"({"body": {"shape": "sphere", "size": 64},
      "simulation": {"duration": 0.001, "frame_interval": 0.001}})");
  r = run("run short.json --out res");
  EXPECT_EQ(r.code, 0) << r.err;
}

TEST_F(CliTest, RunTooManyStepsRefusedUnlessMaxStepsAllows) {
  // 0.01 s at dt = 1e-12 s: 1e10 steps, which would run for days.
  write("slow.json", R"({"body": {"shape": "sphere", "size": 4},
      "simulation": {"dt": 1e-12, "duration": 0.01, "frame_interval": 0.005}})");
  Result r = run("run slow.json --out res");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("slow.json: simulation: 0.01 s at dt = 1e-12 s is 1e+10 steps"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("8.1e+11 vertex-steps, about 6.7 h of wall time"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--max-steps 10000000000"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "res"));
  // --max-steps sets the limit either way: 400 steps refused at 100, run at 400.
  write("short.json", R"({"body": {"shape": "sphere", "size": 4},
      "simulation": {"dt": 1e-5, "duration": 0.004, "frame_interval": 0.002}})");
  r = run("run short.json --out res --max-steps 100");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("is 400 steps"), std::string::npos) << r.err;
  r = run("run short.json --out res --max-steps 400");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out).at("steps").get<int>(), 400);
}

TEST_F(CliTest, RunFrameIntervalBelowDtOneFramePerStepWithWarning) {
  // 25 steps of 1 ms; frames asked every 1 us used to give 10,001 frames, most of them copies.
  // (0.3 ms past the 25th step: the last frame would have repeated the 25th.)
  write("dense.json", R"({"body": {"shape": "sphere", "size": 4},
      "simulation": {"dt": 0.001, "duration": 0.0253, "frame_interval": 1e-6}})");
  const Result r = run("run dense.json --out res");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("frame_interval 1e-06 s is shorter than dt = 0.001 s; writing one frame per step"),
            std::string::npos)
      << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j.at("steps").get<int>(), 25);
  EXPECT_EQ(j.at("frames").get<int>(), 26);
  // Every frame at its own time.
  const std::string pvd = readFile(dir_ / "res" / "run.pvd");
  std::set<std::string> times;
  for (size_t p = pvd.find("timestep=\""); p != std::string::npos; p = pvd.find("timestep=\"", p + 1))
    times.insert(pvd.substr(p + 10, pvd.find('"', p + 10) - p - 10));
  EXPECT_EQ(times.size(), 26u);
}

TEST_F(CliTest, RunUnwritableOutputExit5NothingWritten) {
  write("tiny.json", kTinyScene);
  // sysfs refuses new folders even to root (who bypasses chmod): a read-only location.
  const Result r = run("run tiny.json --out /sys/gradel-cli-test/res");
  EXPECT_EQ(r.code, 5) << r.err;
  EXPECT_EQ(r.err.rfind("gradel: /sys/gradel-cli-test: cannot create: ", 0), 0u) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
  EXPECT_FALSE(fs::exists("/sys/gradel-cli-test"));
}

// A long run started in the background; `signal` stops it once its temporary folder exists.
struct Stopped {
  int status = 0;
  bool sawTemp = false;
};
Stopped runAndSignal(const fs::path& dir, const std::string& scene, int signal) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::chdir(dir.c_str()) != 0) ::_exit(126);
    if (!std::freopen("stdout.txt", "w", stdout) || !std::freopen("stderr.txt", "w", stderr)) ::_exit(126);
    ::execl(GRADEL_CLI_PATH, "gradel", "run", scene.c_str(), "--out", "res", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  Stopped s;
  const std::string prefix = "res.tmp-" + std::to_string(pid) + "-";
  for (int i = 0; i < 200 && !s.sawTemp; ++i) {
    ::usleep(50000);
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().filename().string().rfind(prefix, 0) == 0 && fs::exists(e.path() / "frame_00000.vtu"))
        s.sawTemp = true;
  }
  ::usleep(200000);  // well into the step loop
  ::kill(pid, signal);
  ::waitpid(pid, &s.status, 0);
  return s;
}

// Nothing of `res` (result or temporary folder) in `dir`.
void expectNoResult(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find("res"), std::string::npos) << "left behind: " << e.path();
}

// Minutes of simulated time for a small ball: stopped long before it ends.
const char* kLongScene = R"({"body": {"shape": "sphere", "size": 4},
  "simulation": {"duration": 600, "frame_interval": 0.01, "damping": 1},
  "domain": {"min": [-0.1, 0.0, -0.1], "max": [0.1, 0.2, 0.1]}})";

TEST_F(CliTest, RunSigtermAndSighupLikeSigintExit128PlusSignalNothingWritten) {
  write("long.json", kLongScene);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    SCOPED_TRACE(sig);
    const Stopped s = runAndSignal(dir_, "long.json", sig);
    EXPECT_TRUE(s.sawTemp);
    ASSERT_TRUE(WIFEXITED(s.status)) << "killed by signal " << WTERMSIG(s.status);
    EXPECT_EQ(WEXITSTATUS(s.status), 128 + sig);
    EXPECT_NE(readFile(dir_ / "stderr.txt").find("nothing written"), std::string::npos)
        << readFile(dir_ / "stderr.txt");
    fs::remove(dir_ / "stdout.txt");
    fs::remove(dir_ / "stderr.txt");
    expectNoResult(dir_);
  }
}

TEST_F(CliTest, RunAfterSigkillNextRunRemovesTheLeftover) {
  write("long.json", kLongScene);
  const Stopped s = runAndSignal(dir_, "long.json", SIGKILL);
  ASSERT_TRUE(s.sawTemp);
  EXPECT_TRUE(WIFSIGNALED(s.status));
  size_t leftovers = 0;
  for (const auto& e : fs::directory_iterator(dir_))
    leftovers += e.path().filename().string().rfind("res.tmp-", 0) == 0;
  EXPECT_EQ(leftovers, 1u);  // SIGKILL cannot be caught: the folder stays ...
  write("tiny.json", kTinyScene);
  const Result r = run("run tiny.json --out res");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const auto& e : fs::directory_iterator(dir_))  // ... until the next run of that result
    EXPECT_NE(e.path().filename().string().rfind("res.tmp-", 0), 0u) << "left behind: " << e.path();
  EXPECT_TRUE(fs::exists(dir_ / "res" / "run.pvd"));
}

// A blown-up body keeps finite numbers inside walls: the energy guard stops it (issue 15: drop at
// dt_fraction 0.5 reached 1.4e5 J from a 2.7 J drop and exited 0).
TEST_F(CliTest, RunEnergyBlowUpInsideWallsExit3NamingTheCause) {
  const std::string drop = readFile(fs::path(GRADEL_SOURCE_DIR) / "scenes" / "drop.json");
  json scene = json::parse(drop);
  scene["simulation"]["dt"] = 0.00117;  // dt_fraction 0.5's step (the reader refuses the fraction itself)
  write("big-dt.json", scene.dump());
  Result r = run("run big-dt.json --out res --duration 0.5");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_EQ(r.err.rfind("gradel: simulation diverged at t = ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("kinetic + elastic energy"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("simulation.dt = 0.00117 s"), std::string::npos) << r.err;
  expectNoResult(dir_);

  scene = json::parse(drop);
  scene["simulation"]["integrator"] = "forward_euler";
  scene["simulation"]["dt"] = 0.000234;  // symplectic's auto step; forward Euler's own auto step is stable
  write("euler.json", scene.dump());
  r = run("run euler.json --out res --duration 0.5");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("forward_euler"), std::string::npos) << r.err;
  expectNoResult(dir_);

  // The scene as shipped runs to the end.
  write("drop.json", drop);
  r = run("run drop.json --out res --duration 0.5");
  EXPECT_EQ(r.code, 0) << r.err;
}

// ---- issue 26: exit 2 for what the input caused, start overlaps, tools inside, progress -----------

TEST_F(CliTest, RunOutOfRangeVoxelSizePositionAndMassExit2NamingTheKey) {
  // What the fuzzer reached as internal errors (exit 1): a voxel size of 5e-324 (a vertex without
  // mass) and a body at 1e15 m (rest positions off the voxel lattice).
  expectRejected("tiny.json", R"({"body": {"shape": "sphere", "size": 4, "voxel_size": 5e-324}})", "body.voxel_size");
  expectRejected("huge.json", R"({"body": {"shape": "sphere", "size": 4, "voxel_size": 1e4}})", "body.voxel_size");
  expectRejected("far.json", R"({"body": {"shape": "sphere", "size": 4, "voxel_size": 0.01, "position": [1e15, 0, 0]}})",
                 "body.position");
  expectRejected("light.json",
                 R"({"body": {"shape": "sphere", "size": 4, "voxel_size": 1e-9}, "material": {"density": 1e-300}})",
                 "material.density");
}

TEST_F(CliTest, RunStartOverlapsWarnAndRun) {
  write("overlap.json", R"({
    "bodies": [
      {"name": "a", "shape": "sphere", "size": 6, "voxel_size": 0.01, "position": [-0.06, 0.01, -0.03]},
      {"name": "b", "shape": "sphere", "size": 6, "voxel_size": 0.01, "position": [-0.03, 0.01, -0.03]}],
    "simulation": {"duration": 0.05, "frame_interval": 0.01},
    "domain": {"min": [-0.2, 0.02, -0.2], "max": [0.2, 0.5, 0.2]},
    "manipulators": [{"type": "sphere", "radius": 0.01, "path": [{"t": 0, "position": [-0.03, 0.04, 0]}]}]})");
  const Result r = run("run overlap.json --out res");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("gradel: overlap.json: warning: body 'a' and body 'b' start overlapping"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("beyond the wall ymin of the domain"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("inside manipulator 0"), std::string::npos) << r.err;
}

TEST_F(CliTest, RunToolInsideABodyIsNoDivergence) {
  // Issue 26: a 5 cm tool at the centre of a 12^3 ball exited 3 at t = 0.005 s.
  write("tool.json", R"({
    "body": {"shape": "sphere", "size": 12, "voxel_size": 0.01, "position": [-0.06, -0.06, -0.06]},
    "simulation": {"damping": 2, "gravity": [0, 0, 0], "duration": 0.1, "frame_interval": 0.01},
    "manipulators": [{"type": "sphere", "radius": 0.05, "path": [{"t": 0, "position": [0, 0, 0]}]}]})");
  const Result r = run("run tool.json --out res");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("inside manipulator 0"), std::string::npos) << r.err;
}

TEST_F(CliTest, SlowLayoutShowsProgressOnStderr) {
  Result r = run("layout --shape sphere --size 8", "GRADEL_PROGRESS_AFTER=0");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("gradel: building the gradational layout of"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("done in"), std::string::npos) << r.err;
  r = run("layout --shape sphere --size 8");  // fast: nothing
  EXPECT_EQ(r.code, 0);
  EXPECT_TRUE(r.err.empty()) << r.err;
}

}  // namespace

// `gradel study` hands its arguments to `python3 -m gradel.study` (docs/study.md), with the build
// tree's package on the path; a study itself is tested in python/tests/test_study.py.
TEST_F(CliTest, StudyMissingFileExit2NamingTheFile) {
  if (!fs::exists(fs::path(GRADEL_CLI_PATH).parent_path() / "python" / "gradel"))
    GTEST_SKIP() << "this build tree has no Python package (the sanitizer build makes only gradel and the tests)";
  const Result r = run("study nope.json");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("nope.json: cannot read"), std::string::npos) << r.err;
}

TEST_F(CliTest, StudyWithoutPythonSaysWhatIsMissing) {
  const Result r = run("study nope.json", "GRADEL_PYTHON=/nonexistent/python3");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("cannot start /nonexistent/python3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("python3-distributed"), std::string::npos) << r.err;
}
