// Tests for the command-line program (apps/gradel_main.cpp), run as a separate process:
// bad input gives exit code 2, one line on stderr naming the file and field, and writes
// nothing; `layout --json` prints parseable counts; `run` writes a complete result or none.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

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
  Result run(const std::string& args) {
    const std::string cmd = "cd '" + dir_.string() + "' && '" + std::string(GRADEL_CLI_PATH) + "' " + args + " > stdout.txt 2> stderr.txt";
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

TEST_F(CliTest, run_badSceneFiles_exit2OneLineNothingWritten) {
  expectRejected("unknown.json", R"({"body": {"shape": "sphere", "size": 4, "radiuss": 3}})", "body.radiuss");
  expectRejected("nested.json", R"({"body": {"shape": "sphere", "size": 4}, "manipulators": [{"type": "sphere", "raduis": 1}]})",
                 "manipulators[0].raduis");
  expectRejected("malformed.json", "{\"body\": {\"shape\": \"sphere\",\n \"size\": 4,}}", "invalid JSON: parse error at line 2");
  expectRejected("missing.json", R"({"body": {"size": 4}})", "body.shape");
  expectRejected("range.json", R"({"body": {"shape": "sphere", "size": 4, "voxel_size": -1}})", "body.voxel_size");
  expectRejected("enum.json", R"({"body": {"shape": "sphere", "size": 4}, "simulation": {"integrator": "rk4"}})",
                 "simulation.integrator");
  expectRejected("dim.json", R"({"dim": 2, "body": {"shape": "sphere", "size": 4}, "manipulators": [{"type": "cylinder"}]})",
                 "manipulators[0].type");
  // Valid JSON and schema, but an empty shape: caught when the body is built, still named.
  expectRejected("empty.json", R"({"body": {"shape": "union", "grid": [4, 4, 4],
      "primitives": [{"type": "sphere", "center": [40, 40, 40], "radius": 1}]}})",
                 "empty");
}

TEST_F(CliTest, run_missingFile_exit2) {
  const Result r = run("run nope.json --out result");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "gradel: nope.json: cannot read: No such file or directory\n");
  EXPECT_FALSE(fs::exists(dir_ / "result"));
}

TEST_F(CliTest, badArguments_exit2OneLine) {
  for (const std::string args : {"", "frobnicate", "layout --size abc", "layout --shape cube", "run", "run x.json --threads 0",
                                 "layout --dim 5", "run x.json --duration -1"}) {
    SCOPED_TRACE(args);
    write("x.json", kTinyScene);
    const Result r = run(args);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(r.err.rfind("gradel: ", 0), 0u) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(CliTest, version_printsVersion) {
  const Result r = run("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.out.rfind("gradel ", 0), 0u) << r.out;
}

TEST_F(CliTest, layout_json_hasFewerPairsThanVoxelLayout) {
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

TEST_F(CliTest, layout_text_isAlignedTable) {
  const Result r = run("layout --shape box --size 8 --dim 2 --layout uniform");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("elements"), std::string::npos);
  EXPECT_NE(r.out.find("element-vertex pairs"), std::string::npos);
  EXPECT_NE(r.out.find("hanging vertices"), std::string::npos);
}

TEST_F(CliTest, run_writesCompleteResultAndSummary) {
  write("tiny.json", kTinyScene);
  const Result r = run("run tiny.json --out res --threads 1");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;  // no progress bar when stderr is not a terminal
  const json j = json::parse(r.out);
  for (const char* key : {"scene", "steps", "dt", "wall_seconds", "real_time_factor", "elements", "vertices", "pairs",
                          "final_kinetic_energy", "max_penetration", "max_stress", "out"})
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
  EXPECT_EQ(json::parse(again.out).at("steps").get<int>() * 2, j.at("steps").get<int>());
}

TEST_F(CliTest, run_defaultOut_isOutSlashSceneName) {
  write("tiny.json", R"({"name": "named", "body": {"shape": "box", "size": 2}, "simulation": {"duration": 0.001}})");
  const Result r = run("run tiny.json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "out" / "named" / "run.pvd"));
}

TEST_F(CliTest, run_foreignOutDirectory_isRefused) {
  write("tiny.json", kTinyScene);
  fs::create_directories(dir_ / "docs");
  std::ofstream(dir_ / "docs" / "thesis.tex") << "keep me";
  const Result r = run("run tiny.json --out docs");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("refusing"), std::string::npos) << r.err;
  EXPECT_EQ(readFile(dir_ / "docs" / "thesis.tex"), "keep me");
}

TEST_F(CliTest, run_divergence_exit3NothingWritten) {
  // dt far above the stability limit (the smallest period here is ~2 ms): the state blows up
  // to inf/NaN within a few hundred steps.
  write("unstable.json", R"({"body": {"shape": "sphere", "size": 6, "velocity": [0, 0, 1]},
      "simulation": {"dt": 0.05, "gravity": [0, 0, 0], "duration": 100, "frame_interval": 10},
      "manipulators": [{"type": "sphere", "radius": 0.02, "path": [{"t": 0, "position": [0.03, 0.03, 0.1]}]}]})");
  const Result r = run("run unstable.json --out res");
  EXPECT_EQ(r.code, 3) << r.err << r.out;
  EXPECT_NE(r.err.find("simulation diverged at t="), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("try a smaller dt"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());
  EXPECT_FALSE(fs::exists(dir_ / "res"));
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find("res"), std::string::npos) << "left behind: " << e.path();
}

}  // namespace
