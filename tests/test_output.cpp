// Tests for the result writers (src/output.cpp): VTK frames decode back to the model and state,
// the .pvd and metrics.csv have the documented form, and OutputDirectory publishes a result
// atomically or leaves everything as it was.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "gradel/output.h"

namespace gradel {
namespace {
namespace fs = std::filesystem;
// metrics.csv's columns of each wall (after the walls together), contacts.h kWalls order.
constexpr const char* kPerWallColumns =
    ",wall_xmin_fx,wall_xmin_fy,wall_xmin_fz,wall_xmin_tx,wall_xmin_ty,wall_xmin_tz,wall_xmax_fx,wall_xmax_fy,wall_"
    "xmax_fz,wall_xmax_tx,wall_xmax_ty,wall_xmax_tz,wall_ymin_fx,wall_ymin_fy,wall_ymin_fz,wall_ymin_tx,wall_ymin_ty,"
    "wall_ymin_tz"
    ",wall_ymax_fx,wall_ymax_fy,wall_ymax_fz,wall_ymax_tx,wall_ymax_ty,wall_ymax_tz,wall_zmin_fx,wall_zmin_fy,wall_"
    "zmin_fz,wall_zmin_tx,wall_zmin_ty,wall_zmin_tz,wall_zmax_fx,wall_zmax_fy,wall_zmax_fz,wall_zmax_tx,wall_zmax_ty,"
    "wall_zmax_tz";

// A fresh, empty scratch directory per test, removed afterwards.
class OutputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("gradel-output-test-" + std::to_string(::getpid()) + "-" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
};

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void writeFile(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

// Entries of a directory, sorted, as names.
std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// ---- VTK ------------------------------------------------------------------------

// Two 2D elements by hand: a unit square [0,1]^2 (4 corners) and, beside it, [1,2]x[0,1]
// carrying the hanging vertex (1, 0.5) of a finer neighbour on its left edge.
RestModel twoElements2d() {
  RestModel m;
  m.dim = 2;
  m.restPositions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0),  Vec3(0, 1, 0),
                     Vec3(1, 1, 0), Vec3(2, 1, 0), Vec3(1, 0.5, 0)};
  m.level = {0, 1};
  m.stiffness = {1, 1};
  m.size = {1, 1};
  m.elemStart = {0, 4, 9};
  m.elemVerts = {0, 1, 3, 4, /**/ 1, 2, 4, 5, 6};
  for (size_t e = 0; e < 2; ++e) {
    Vec3 c = Vec3::Zero();
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) c += m.restPositions[m.elemVerts[p]];
    m.restCentroids.push_back(c / Real(m.elemStart[e + 1] - m.elemStart[e]));
  }
  return m;
}

State stateOf(const RestModel& m) {
  State s;
  s.positions = m.restPositions;
  for (size_t i = 0; i < s.positions.size(); ++i) s.velocities.push_back(Vec3(0.5 * Real(i), -1.0 / 3.0, 0));
  return s;
}

// The text between <DataArray ... Name="name" ...> and </DataArray>.
std::string dataArrayText(const std::string& xml, const std::string& name) {
  const size_t at = xml.find("Name=\"" + name + "\"");
  if (at == std::string::npos) return "";
  const size_t open = xml.find('>', at) + 1;
  return xml.substr(open, xml.find("</DataArray>", open) - open);
}

std::vector<unsigned char> base64Decode(const std::string& text) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  std::vector<unsigned char> out;
  uint32_t acc = 0;
  int bits = 0;
  for (char c : text) {
    const int v = value(c);
    if (v < 0) continue;  // whitespace and '=' padding
    acc = (acc << 6) | uint32_t(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<unsigned char>((acc >> bits) & 0xFF));
    }
  }
  return out;
}

// A binary DataArray decoded: checks the UInt32 byte-count header, returns the values.
template <class T>
std::vector<T> decodeBinary(const std::string& xml, const std::string& name) {
  const std::vector<unsigned char> raw = base64Decode(dataArrayText(xml, name));
  EXPECT_GE(raw.size(), 4u);
  if (raw.size() < 4) return {};
  uint32_t bytes = 0;
  std::memcpy(&bytes, raw.data(), 4);
  EXPECT_EQ(bytes, raw.size() - 4) << name;
  std::vector<T> v((raw.size() - 4) / sizeof(T));
  std::memcpy(v.data(), raw.data() + 4, v.size() * sizeof(T));
  return v;
}

template <class T>
std::vector<T> decodeAscii(const std::string& xml, const std::string& name) {
  std::istringstream in(dataArrayText(xml, name));
  std::vector<T> v;
  double x;
  while (in >> x) v.push_back(T(x));
  return v;
}

TEST_F(OutputTest, WriteVtuBinaryDecodesToModelAndState) {
  const RestModel m = twoElements2d();
  const State s = stateOf(m);
  const std::vector<Real> vstress = {0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6}, estress = {1.5, 2.5};
  const std::vector<Real> vstrain = {7, 6, 5, 4, 3, 2, 1}, estrain = {0.25, 0.75};
  writeVtu(root_ / "f.vtu", m, s, vstress, estress, VtkEncoding::Base64, vstrain, estrain);
  const std::string xml = readFile(root_ / "f.vtu");
  EXPECT_NE(xml.find("type=\"UnstructuredGrid\""), std::string::npos);
  EXPECT_NE(xml.find("NumberOfPoints=\"7\" NumberOfCells=\"2\""), std::string::npos);

  const auto points = decodeBinary<double>(xml, "position");
  ASSERT_EQ(points.size(), 21u);
  for (size_t i = 0; i < 7; ++i)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(points[3 * i + c], s.positions[i][c]);
  const auto vel = decodeBinary<double>(xml, "velocity");
  ASSERT_EQ(vel.size(), 21u);
  EXPECT_EQ(vel[3 * 5 + 0], 2.5);
  EXPECT_EQ(vel[3 * 5 + 1], -1.0 / 3.0);  // exact: binary keeps every bit
  EXPECT_EQ(decodeBinary<double>(xml, "stress"), vstress);
  EXPECT_EQ(decodeBinary<double>(xml, "element_stress"), estress);
  EXPECT_EQ(decodeBinary<double>(xml, "strain"), vstrain);  // the dimensionless measure, its own name
  EXPECT_EQ(decodeBinary<double>(xml, "element_strain"), estrain);
  EXPECT_EQ(decodeBinary<uint8_t>(xml, "level"), (std::vector<uint8_t>{0, 1}));
  EXPECT_EQ(decodeBinary<int32_t>(xml, "element_id"), (std::vector<int32_t>{0, 1}));
  EXPECT_EQ(decodeBinary<int32_t>(xml, "offsets"), (std::vector<int32_t>{4, 9}));
  EXPECT_EQ(decodeBinary<uint8_t>(xml, "types"), (std::vector<uint8_t>{kVtkPolygon, kVtkPolygon}));
  // 2D cells are polygons in angular order about the element's centroid: the outline.
  EXPECT_EQ(decodeBinary<int32_t>(xml, "connectivity"), (std::vector<int32_t>{0, 1, 4, 3, /**/ 1, 2, 5, 4, 6}));
  EXPECT_NE(xml.find(R"(<DataArray type="Int32" Name="connectivity" format="binary">)"), std::string::npos);
}

// An appended (raw) DataArray: its offset in the element, the UInt32 byte count and the values
// after the '_' that opens the appended block.
template <class T>
std::vector<T> decodeAppended(const std::string& file, const std::string& name) {
  const size_t at = file.find("Name=\"" + name + "\"");
  if (at == std::string::npos) return {};
  const size_t tagEnd = file.find('>', at);
  const size_t off = file.find("offset=\"", at);
  EXPECT_LT(off, tagEnd) << name;
  const size_t offset = std::stoul(file.substr(off + 8));
  const size_t block = file.find("<AppendedData encoding=\"raw\">");
  EXPECT_NE(block, std::string::npos);
  const size_t base = file.find('_', block) + 1;
  uint32_t bytes = 0;
  std::memcpy(&bytes, file.data() + base + offset, 4);
  std::vector<T> v(bytes / sizeof(T));
  EXPECT_EQ(bytes, v.size() * sizeof(T)) << name;
  std::memcpy(v.data(), file.data() + base + offset + 4, bytes);
  return v;
}

// The default encoding (`gradel run`'s frames): the same arrays as the base64 file, bit for bit,
// as raw appended data; a buffer refilled for another frame holds exactly that frame.
TEST_F(OutputTest, WriteVtuRawAppendedHoldsTheSameArrays) {
  RestModel m = twoElements2d();
  const State s = stateOf(m);
  const std::vector<Real> vstress = {0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6}, estress = {1.5, 2.5};
  writeVtu(root_ / "b.vtu", m, s, vstress, estress, VtkEncoding::Base64);
  writeVtu(root_ / "r.vtu", m, s, vstress, estress);  // Raw is the default
  const std::string b64 = readFile(root_ / "b.vtu"), raw = readFile(root_ / "r.vtu");
  EXPECT_NE(raw.find(R"(<DataArray type="Float64" Name="position" NumberOfComponents="3" format="appended" offset=")"),
            std::string::npos);
  EXPECT_EQ(raw.find("format=\"binary\""), std::string::npos);
  EXPECT_EQ(raw.substr(raw.size() - 30), "\n  </AppendedData>\n</VTKFile>\n");
  EXPECT_LT(raw.size(), b64.size());
  EXPECT_EQ(decodeAppended<double>(raw, "position"), decodeBinary<double>(b64, "position"));
  EXPECT_EQ(decodeAppended<double>(raw, "velocity"), decodeBinary<double>(b64, "velocity"));
  EXPECT_EQ(decodeAppended<double>(raw, "stress"), vstress);
  EXPECT_EQ(decodeAppended<double>(raw, "element_stress"), estress);
  EXPECT_EQ(decodeAppended<uint8_t>(raw, "level"), (std::vector<uint8_t>{0, 1}));
  EXPECT_EQ(decodeAppended<int32_t>(raw, "element_id"), (std::vector<int32_t>{0, 1}));
  EXPECT_EQ(decodeAppended<int32_t>(raw, "offsets"), (std::vector<int32_t>{4, 9}));
  EXPECT_EQ(decodeAppended<int32_t>(raw, "connectivity"), (std::vector<int32_t>{0, 1, 4, 3, /**/ 1, 2, 5, 4, 6}));
  EXPECT_EQ(decodeAppended<uint8_t>(raw, "types"), (std::vector<uint8_t>{kVtkPolygon, kVtkPolygon}));

  // A buffer reused for a smaller frame (no stress) holds that frame only.
  VtuBytes bytes;
  encodeVtu(bytes, m, s, wholeModelBody(m), vstress, estress);
  encodeVtu(bytes, m, s, wholeModelBody(m), {}, {});
  writeVtu(root_ / "again.vtu", bytes);
  writeVtu(root_ / "fresh.vtu", m, s, std::vector<Real>{});
  EXPECT_EQ(readFile(root_ / "again.vtu"), readFile(root_ / "fresh.vtu"));
}

// Frames written on the writer's thread are the files writeVtu writes, in order; a write that
// fails is reported by finish() with the path, not lost.
TEST_F(OutputTest, FrameFileWriterWritesWholeFilesAndReportsFailures) {
  const RestModel m = twoElements2d();
  State s = stateOf(m);
  {
    FrameFileWriter w;
    for (int f = 0; f < 4; ++f) {
      s.positions[0].x() = 0.25 * f;
      encodeVtu(w.buffer(), m, s, wholeModelBody(m), {}, {});
      w.submit(root_ / ("w" + std::to_string(f) + ".vtu"));
    }
    w.finish();
  }
  for (int f = 0; f < 4; ++f) {
    s.positions[0].x() = 0.25 * f;
    writeVtu(root_ / "ref.vtu", m, s, std::vector<Real>{});
    EXPECT_EQ(readFile(root_ / ("w" + std::to_string(f) + ".vtu")), readFile(root_ / "ref.vtu")) << f;
  }
  FrameFileWriter w;
  encodeVtu(w.buffer(), m, s, wholeModelBody(m), {}, {});
  w.submit(root_ / "no-such-dir" / "x.vtu");
  try {
    w.finish();
    ADD_FAILURE() << "a failed write was not reported";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-dir/x.vtu"), std::string::npos) << e.what();
  }
}

TEST_F(OutputTest, WriteVtuAsciiMatchesBinary) {
  RestModel m = twoElements2d();
  m.dim = 3;  // the same vertices as a 3D model: convex point sets in stored order
  const State s = stateOf(m);
  writeVtu(root_ / "a.vtu", m, s, {}, {}, VtkEncoding::Ascii);
  const std::string xml = readFile(root_ / "a.vtu");
  EXPECT_NE(xml.find("format=\"ascii\""), std::string::npos);
  EXPECT_EQ(xml.find("format=\"binary\""), std::string::npos);
  EXPECT_EQ(xml.find("Name=\"stress\""), std::string::npos);               // no stress given, none written
  EXPECT_EQ(xml.find("Name=\"strain\""), std::string::npos);
  EXPECT_EQ(decodeAscii<double>(xml, "velocity")[3 * 2 + 1], -1.0 / 3.0);  // shortest round-trip text
  EXPECT_EQ(decodeAscii<int64_t>(xml, "connectivity"), (std::vector<int64_t>{0, 1, 3, 4, 1, 2, 4, 5, 6}));
  EXPECT_EQ(decodeAscii<int>(xml, "types"), (std::vector<int>{kVtkConvexPointSet, kVtkConvexPointSet}));
}

TEST_F(OutputTest, WriteVtuSizeMismatchThrows) {
  const RestModel m = twoElements2d();
  State s = stateOf(m);
  EXPECT_THROW(writeVtu(root_ / "x.vtu", m, s, {1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(writeVtu(root_ / "x.vtu", m, s, {}, {}, VtkEncoding::Base64, {}, {1.0}), std::invalid_argument);
  s.velocities.pop_back();
  EXPECT_THROW(writeVtu(root_ / "x.vtu", m, s, {}), std::invalid_argument);
}

TEST_F(OutputTest, WriteVtuUnwritablePathThrowsIoError) {
  const RestModel m = twoElements2d();
  EXPECT_THROW(writeVtu(root_ / "no-such-dir" / "x.vtu", m, stateOf(m), {}), IoError);
}

// The message of the IoError `f` throws, or "" when it throws nothing (other types fail the test).
template <class F>
std::string ioErrorOf(F&& f) {
  try {
    f();
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

// /dev/full answers every write with ENOSPC: a full disk, without filling one.
TEST_F(OutputTest, DiskFullIsIoErrorNamingPathAndReason) {
  const RestModel m = twoElements2d();
  const std::string nospace = std::strerror(ENOSPC);
  std::string msg = ioErrorOf([&] { writeVtu("/dev/full", m, stateOf(m), {}); });
  EXPECT_NE(msg.find("/dev/full"), std::string::npos) << msg;
  EXPECT_NE(msg.find(nospace), std::string::npos) << msg;
  msg = ioErrorOf([&] { writePvd("/dev/full", {{0.0, frameFileName(0)}}); });
  EXPECT_NE(msg.find(nospace), std::string::npos) << msg;
  msg = ioErrorOf([&] {
    MetricsCsv csv("/dev/full");
    for (int i = 0; i < 1000; ++i) csv.append(Metrics{});  // more than stdio's buffer
    csv.close();
  });
  EXPECT_NE(msg.find("/dev/full"), std::string::npos) << msg;
  EXPECT_NE(msg.find(nospace), std::string::npos) << msg;
}

// A folder the system will not let us create (sysfs refuses even root, who bypasses chmod).
TEST_F(OutputTest, OutputDirectoryUnwritableLocationIsIoErrorAndLeavesNothing) {
  const std::string msg = ioErrorOf([] { OutputDirectory("/sys/gradel-output-test/result", "run.pvd"); });
  EXPECT_NE(msg.find("/sys/gradel-output-test"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists("/sys/gradel-output-test"));
  // A file where a folder is expected is the user's path mistake, not the system's.
  writeFile(root_ / "file", "x");
  EXPECT_THROW(OutputDirectory(root_ / "file" / "sub" / "result", "run.pvd"), InputError);
}

// A pid that no process has: a child that has exited and been reaped.
pid_t deadPid() {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(0);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return pid;
}

TEST_F(OutputTest, StaleTemporariesOfDeadRunsAreRemovedOthersKept) {
  const fs::path target = root_ / "result";
  const fs::path dead = root_ / ("result.tmp-" + std::to_string(deadPid()) + "-Ab12Cd");
  const fs::path alive = root_ / ("result.tmp-" + std::to_string(::getppid()) + "-Ab12Cd");  // our parent lives
  const fs::path oldStyle = root_ / "result.tmp-Ab12Cd";
  const fs::path other = root_ / ("other.tmp-" + std::to_string(deadPid()) + "-Ab12Cd");
  for (const fs::path& p : {dead, alive, oldStyle, other}) {
    fs::create_directories(p);
    writeFile(p / "frame_00000.vtu", "x");
  }
  {
    OutputDirectory dir(target, "run.pvd");  // a new run of the same target cleans up first
    EXPECT_FALSE(fs::exists(dead));
    EXPECT_TRUE(fs::exists(alive));
    EXPECT_TRUE(fs::exists(oldStyle));
    EXPECT_TRUE(fs::exists(other));
    // Its own temporary folder carries its pid, so that a later run can tell.
    EXPECT_EQ(dir.path().filename().string().rfind("result.tmp-" + std::to_string(::getpid()) + "-", 0), 0u)
        << dir.path();
  }
  EXPECT_EQ(removeStaleTemporaries(target), 0u);
  EXPECT_EQ(removeStaleTemporaries(root_ / "other"), 1u);
  EXPECT_FALSE(fs::exists(other));

  // A pid that looks dead here but whose run holds the lock (another pid namespace) is kept.
  const fs::path foreign = root_ / ("result.tmp-" + std::to_string(deadPid()) + "-Lk12Cd");
  fs::create_directories(foreign);
  writeFile(foreign / ".lock", "");
  const int fd = ::open((foreign / ".lock").c_str(), O_RDWR);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  EXPECT_EQ(removeStaleTemporaries(target), 0u);
  EXPECT_TRUE(fs::exists(foreign));
  ::close(fd);
  EXPECT_EQ(removeStaleTemporaries(target), 1u);
  EXPECT_FALSE(fs::exists(foreign));
}

TEST_F(OutputTest, WritePvdListsFramesWithTimes) {
  writePvd(root_ / "run.pvd", {{0.0, frameFileName(0)}, {0.125, frameFileName(1)}});
  const std::string xml = readFile(root_ / "run.pvd");
  EXPECT_NE(xml.find("type=\"Collection\""), std::string::npos);
  EXPECT_NE(xml.find("timestep=\"0\" group=\"\" part=\"0\" file=\"frame_00000.vtu\""), std::string::npos) << xml;
  EXPECT_NE(xml.find("timestep=\"0.125\" group=\"\" part=\"0\" file=\"frame_00001.vtu\""), std::string::npos) << xml;
}

// ---- metrics ----------------------------------------------------------------------

TEST_F(OutputTest, MetricsCsvHeaderAndRowsRoundTrip) {
  Metrics a;
  a.time = 0.1;
  a.kineticEnergy = 1.0 / 3.0;
  a.linearMomentum = Vec3(1, 2, 3);
  a.angularMomentum = Vec3(-4, 5e-300, 6);
  a.minElementDet = -0.5;
  a.maxStress = 2500.0;
  a.maxStrain = 0.25;
  {
    MetricsCsv csv(root_ / "metrics.csv");
    csv.append(a);
    csv.append(Metrics{});
    csv.close();
  }
  std::istringstream in(readFile(root_ / "metrics.csv"));
  std::string header, row1, row2, extra;
  std::getline(in, header);
  std::getline(in, row1);
  std::getline(in, row2);
  EXPECT_FALSE(std::getline(in, extra));
  EXPECT_EQ(header,
            "time,kinetic_energy,elastic_energy,gravity_energy,px,py,pz,Lx,Ly,Lz,max_stress,max_penetration,"
            "max_contact_depth,min_element_det,wall_fx,wall_fy,wall_fz,wall_tx,wall_ty,wall_tz" +
                std::string(kPerWallColumns) + ",max_strain");
  std::vector<double> values;
  std::istringstream cells(row1);
  for (std::string cell; std::getline(cells, cell, ',');) values.push_back(std::stod(cell));
  ASSERT_EQ(values.size(), 20u + 36u + 1u);
  EXPECT_EQ(values[10], 2500.0);  // max_stress [Pa]
  EXPECT_EQ(values.back(), 0.25);  // max_strain [-], last
  EXPECT_EQ(values[0], 0.1);
  EXPECT_EQ(values[1], 1.0 / 3.0);  // full precision
  EXPECT_EQ(values[6], 3.0);
  EXPECT_EQ(values[8], 5e-300);
  EXPECT_EQ(values[13], -0.5);
  std::string zeros = "0";
  for (int i = 1; i < 20 + 36 + 1; ++i) zeros += ",0";  // the per-wall forces and max_strain too
  EXPECT_EQ(row2, zeros);
}

// ---- OutputDirectory ----------------------------------------------------------------

TEST_F(OutputTest, OutputDirectoryCommitPublishesTarget) {
  const fs::path target = root_ / "deep" / "er" / "run";
  {
    OutputDirectory out(target, "run.pvd");
    EXPECT_FALSE(fs::exists(target));
    EXPECT_EQ(out.path().parent_path(), target.parent_path());  // a sibling, so rename() is atomic
    writeFile(out.file("a.txt"), "new");
    out.commit();
    EXPECT_TRUE(out.committed());
  }
  EXPECT_EQ(readFile(target / "a.txt"), "new");
  EXPECT_EQ(listing(target.parent_path()), std::vector<std::string>{"run"});  // no temporary left
}

TEST_F(OutputTest, OutputDirectoryAbortLeavesNothing) {
  const fs::path target = root_ / "deep" / "er" / "run";
  {
    OutputDirectory out(target, "run.pvd");
    writeFile(out.file("a.txt"), "partial");
  }                                          // destroyed without commit: as after an error or a divergence
  EXPECT_FALSE(fs::exists(root_ / "deep"));  // the parents it created are gone too
  EXPECT_TRUE(listing(root_).empty());
}

TEST_F(OutputTest, OutputDirectoryExistingTargetKeptOnAbortReplacedOnCommit) {
  const fs::path target = root_ / "run";
  fs::create_directories(target);
  writeFile(target / "run.pvd", "old");
  writeFile(target / "stale.txt", "old");
  {
    OutputDirectory out(target, "run.pvd");
    writeFile(out.file("run.pvd"), "new");
    EXPECT_EQ(readFile(target / "run.pvd"), "old");  // untouched until commit
  }
  EXPECT_EQ(listing(target), (std::vector<std::string>{"run.pvd", "stale.txt"}));
  EXPECT_EQ(readFile(target / "run.pvd"), "old");
  {
    OutputDirectory out(target, "run.pvd");
    writeFile(out.file("run.pvd"), "new");
    out.commit();
  }
  EXPECT_EQ(listing(target), std::vector<std::string>{"run.pvd"});  // replaced as a whole
  EXPECT_EQ(readFile(target / "run.pvd"), "new");
  EXPECT_EQ(listing(root_), std::vector<std::string>{"run"});  // the old copy was deleted
}

TEST_F(OutputTest, OutputDirectoryRefusesToReplaceForeignDirectoryOrFile) {
  fs::create_directories(root_ / "home");
  writeFile(root_ / "home" / "precious.txt", "keep");
  EXPECT_THROW(OutputDirectory(root_ / "home", "run.pvd"), InputError);
  EXPECT_EQ(readFile(root_ / "home" / "precious.txt"), "keep");
  writeFile(root_ / "file", "x");
  EXPECT_THROW(OutputDirectory(root_ / "file", "run.pvd"), InputError);
  EXPECT_THROW(OutputDirectory(root_ / "..", "run.pvd"), InputError);        // the non-empty temp directory
  EXPECT_THROW(OutputDirectory(root_ / "a" / "..", "run.pvd"), InputError);  // normalises to root_ itself
  EXPECT_EQ(listing(root_), (std::vector<std::string>{"file", "home"}));     // no temporaries left
  // An empty existing directory is fine to replace.
  fs::create_directories(root_ / "empty");
  OutputDirectory ok(root_ / "empty", "run.pvd");
  ok.commit();
}

TEST_F(OutputTest, OutputDirectoryTrailingSlashNamesTheDirectory) {
  {
    OutputDirectory out(root_.string() + "/res/", "run.pvd");
    EXPECT_EQ(out.target().filename(), "res");
    out.commit();
  }
  EXPECT_TRUE(fs::is_directory(root_ / "res"));
}

}  // namespace
}  // namespace gradel
