#include "gradel/output.h"

#include <fcntl.h>     // open
#include <signal.h>    // kill (POSIX)
#include <stdlib.h>    // mkdtemp (POSIX)
#include <sys/file.h>  // flock
#include <unistd.h>    // rmdir, getpid

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <initializer_list>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <type_traits>

namespace gradel {
namespace fs = std::filesystem;

namespace {

// ---- number and byte formatting ----------------------------------------------

// Shortest text that reads back to the same value (no precision is lost in the CSV or in
// ASCII VTK files, and no noise digits are added).
template <class T>
void appendNumber(std::string& out, T x) {
  char buf[32];
  std::to_chars_result r;
  if constexpr (std::is_floating_point_v<T>)
    r = std::to_chars(buf, buf + sizeof buf, x);
  else
    r = std::to_chars(buf, buf + sizeof buf, std::conditional_t<(sizeof(T) < sizeof(int)), int, T>(x));
  out.append(buf, r.ptr);
}

void appendBase64(std::string& out, const unsigned char* data, size_t n) {
  static const char kTable[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  // Sized once and filled through a pointer: appending a character at a time (a capacity check
  // each) made this 7 % of box-realtime's `gradel run` (perf), more than the file writes.
  const size_t start = out.size();
  out.resize(start + (n + 2) / 3 * 4);
  char* o = out.data() + start;
  size_t i = 0;
  for (; i + 3 <= n; i += 3, o += 4) {
    const uint32_t v = uint32_t(data[i]) << 16 | uint32_t(data[i + 1]) << 8 | data[i + 2];
    o[0] = kTable[v >> 18], o[1] = kTable[(v >> 12) & 63], o[2] = kTable[(v >> 6) & 63], o[3] = kTable[v & 63];
  }
  if (n - i == 1) {
    const uint32_t v = uint32_t(data[i]) << 16;
    o[0] = kTable[v >> 18], o[1] = kTable[(v >> 12) & 63], o[2] = '=', o[3] = '=';
  } else if (n - i == 2) {
    const uint32_t v = uint32_t(data[i]) << 16 | uint32_t(data[i + 1]) << 8;
    o[0] = kTable[v >> 18], o[1] = kTable[(v >> 12) & 63], o[2] = kTable[(v >> 6) & 63], o[3] = '=';
  }
}

template <class T>
const char* vtkTypeName() {
  if constexpr (std::is_same_v<T, double>) return "Float64";
  if constexpr (std::is_same_v<T, int32_t>) return "Int32";
  if constexpr (std::is_same_v<T, uint8_t>) return "UInt8";
}

// Stores value i of an array of T at `dst` (any alignment: the appended block packs arrays
// after 4-byte headers).
template <class T>
void store(unsigned char* dst, size_t i, T value) {
  std::memcpy(dst + i * sizeof(T), &value, sizeof(T));
}

// Where one frame's <DataArray>s go. Raw: an empty element with its offset into the appended
// block, which holds per array a UInt32 byte count and the raw values in native byte order
// (vtkXMLDataParser's "appended" data, encoding "raw"). Base64 (VTK XML "binary",
// uncompressed): base64 of the same count-and-values stream inside the element. Ascii: text.
// `fill(dst)` writes the array's count values of T to dst (through store()).
struct ArraySink {
  VtkEncoding encoding;
  VtuBytes& out;
  std::vector<unsigned char> scratch;  // Base64 / Ascii: the values before they are encoded

  template <class T, class Fill>
  void add(const char* name, int components, size_t count, Fill&& fill) {
    const size_t bytes = count * sizeof(T);
    if (bytes > UINT32_MAX) throw std::runtime_error("writeVtu: array larger than 4 GiB");
    const uint32_t header = uint32_t(bytes);
    std::string& x = out.xml;
    x += "        <DataArray type=\"";
    x += vtkTypeName<T>();
    x += "\" Name=\"";
    x += name;
    x += "\"";
    if (components > 1) x += " NumberOfComponents=\"" + std::to_string(components) + "\"";
    if (encoding == VtkEncoding::Raw) {
      x += " format=\"appended\" offset=\"" + std::to_string(out.appended.size()) + "\"/>\n";
      const size_t at = out.appended.size();
      out.appended.resize(at + sizeof header + bytes);
      unsigned char* dst = reinterpret_cast<unsigned char*>(out.appended.data()) + at;
      std::memcpy(dst, &header, sizeof header);
      fill(dst + sizeof header);
      return;
    }
    scratch.resize(sizeof header + bytes);
    std::memcpy(scratch.data(), &header, sizeof header);
    fill(scratch.data() + sizeof header);
    if (encoding == VtkEncoding::Base64) {
      x += " format=\"binary\">\n";
      appendBase64(x, scratch.data(), scratch.size());
      x += '\n';
    } else {
      x += " format=\"ascii\">\n";
      for (size_t i = 0; i < count; ++i) {
        T v;
        std::memcpy(&v, scratch.data() + sizeof header + i * sizeof(T), sizeof v);
        appendNumber(x, v);
        x += (i + 1) % size_t(std::max(components, 1)) == 0 || i + 1 == count ? '\n' : ' ';
      }
    }
    x += "        </DataArray>\n";
  }

  // `count` values of T copied from `values` (a slice of a vector).
  template <class T>
  void add(const char* name, const T* values, size_t count) {
    add<T>(name, 1, count, [&](unsigned char* dst) {
      if (count) std::memcpy(dst, values, count * sizeof(T));
    });
  }
};

[[noreturn]] void throwWriteError(const fs::path& file, int err) {
  throw IoError("cannot write " + file.string() + ": " + std::strerror(err ? err : EIO));
}

// Writes `parts` one after the other into `file` (created or truncated).
void writeWholeFile(const fs::path& file, std::initializer_list<const std::string*> parts) {
  std::FILE* f = std::fopen(file.c_str(), "wb");
  if (!f) throwWriteError(file, errno);
  errno = 0;
  bool wrote = true;
  for (const std::string* p : parts) wrote = wrote && std::fwrite(p->data(), 1, p->size(), f) == p->size();
  wrote = wrote && std::fflush(f) == 0;
  const int err = errno;
  if (std::fclose(f) != 0 || !wrote) throwWriteError(file, wrote ? errno : err);
}

void writeWholeFile(const fs::path& file, const std::string& text) { writeWholeFile(file, {&text}); }

std::string xmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

constexpr const char* kByteOrder = std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian";

}  // namespace

// ---- VTK ------------------------------------------------------------------------

std::string frameFileName(size_t index, const std::string& body) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%05zu.vtu", index);
  return (body.empty() ? std::string("frame") : body) + buf;
}

void writeVtu(const fs::path& file, const RestModel& model, const State& state, const std::vector<Real>& vertexStress,
              const std::vector<Real>& elementStress, VtkEncoding encoding, const std::vector<Real>& vertexStrain,
              const std::vector<Real>& elementStrain) {
  writeVtu(file, model, state, wholeModelBody(model), vertexStress, elementStress, encoding, vertexStrain,
           elementStrain);
}

void writeVtu(const fs::path& file, const RestModel& model, const State& state, const BodyRange& body,
              const std::vector<Real>& vertexStress, const std::vector<Real>& elementStress, VtkEncoding encoding,
              const std::vector<Real>& vertexStrain, const std::vector<Real>& elementStrain) {
  VtuBytes bytes;
  encodeVtu(bytes, model, state, body, vertexStress, elementStress, encoding, vertexStrain, elementStrain);
  writeVtu(file, bytes);
}

void writeVtu(const fs::path& file, const VtuBytes& bytes) {
  static const std::string kAppendedOpen = "  <AppendedData encoding=\"raw\">\n   _";
  static const std::string kAppendedClose = "\n  </AppendedData>\n</VTKFile>\n", kClose = "</VTKFile>\n";
  if (bytes.appended.empty())
    writeWholeFile(file, {&bytes.xml, &kClose});
  else
    writeWholeFile(file, {&bytes.xml, &kAppendedOpen, &bytes.appended, &kAppendedClose});
}

void encodeVtu(VtuBytes& out, const RestModel& model, const State& state, const BodyRange& body,
               const std::vector<Real>& vertexStress, const std::vector<Real>& elementStress, VtkEncoding encoding,
               const std::vector<Real>& vertexStrain, const std::vector<Real>& elementStrain) {
  const size_t NV = model.numVertices(), NE = model.numElements();
  if (state.positions.size() != NV || state.velocities.size() != NV)
    throw std::invalid_argument("writeVtu: state does not match the model's vertex count");
  if (!vertexStress.empty() && vertexStress.size() != NV)
    throw std::invalid_argument("writeVtu: vertexStress must be empty or have one value per vertex");
  if (!elementStress.empty() && elementStress.size() != NE)
    throw std::invalid_argument("writeVtu: elementStress must be empty or have one value per element");
  if (!vertexStrain.empty() && vertexStrain.size() != NV)
    throw std::invalid_argument("writeVtu: vertexStrain must be empty or have one value per vertex");
  if (!elementStrain.empty() && elementStrain.size() != NE)
    throw std::invalid_argument("writeVtu: elementStrain must be empty or have one value per element");
  if (model.elemStart.size() != NE + 1 || model.level.size() != NE)
    throw std::invalid_argument("writeVtu: inconsistent rest model");
  if (body.vertexBegin > body.vertexEnd || body.vertexEnd > NV || body.elementBegin > body.elementEnd ||
      body.elementEnd > NE)
    throw std::invalid_argument("writeVtu: the body's range is not in the model");
  const size_t v0 = body.vertexBegin, e0 = body.elementBegin;
  const size_t nv = body.numVertices(), ne = body.numElements();
  const uint32_t p0 = model.elemStart[e0], pairs = model.elemStart[body.elementEnd] - p0;
  if (nv > size_t(INT32_MAX) || pairs > uint32_t(INT32_MAX))
    throw std::invalid_argument("writeVtu: more than 2^31 points or cell corners in one file");

  out.xml.clear(), out.appended.clear();  // capacity kept: a caller's buffer is reused frame after frame
  ArraySink sink{encoding, out, {}};
  std::string& x = out.xml;
  x += "<?xml version=\"1.0\"?>\n";
  x += std::string("<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"") + kByteOrder +
       "\" header_type=\"UInt32\">\n";
  x += "  <UnstructuredGrid>\n";
  x += "    <Piece NumberOfPoints=\"" + std::to_string(nv) + "\" NumberOfCells=\"" + std::to_string(ne) + "\">\n";
  x += vertexStress.empty() ? "      <PointData Vectors=\"velocity\">\n"
                            : "      <PointData Scalars=\"stress\" Vectors=\"velocity\">\n";
  // Positions and velocities: 3 doubles per vertex, stored packed (Vec3 is Eigen's unpadded
  // Vector3d), copied in one piece.
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  auto vectors = [&](const char* name, const std::vector<Vec3>& v) {
    sink.add<double>(name, 3, 3 * nv, [&](unsigned char* dst) {
      if (nv) std::memcpy(dst, v[v0].data(), nv * sizeof(Vec3));
    });
  };
  vectors("velocity", state.velocities);
  if (!vertexStress.empty()) sink.add<double>("stress", vertexStress.data() + v0, nv);
  if (!vertexStrain.empty()) sink.add<double>("strain", vertexStrain.data() + v0, nv);
  x += "      </PointData>\n";
  x += "      <CellData Scalars=\"level\">\n";
  sink.add<uint8_t>("level", model.level.data() + e0, ne);
  sink.add<int32_t>("element_id", 1, ne, [&](unsigned char* dst) {
    for (size_t e = 0; e < ne; ++e) store(dst, e, int32_t(e));
  });
  if (model.materials.size() > 1 && model.elementMaterial.size() == NE) {
    // A body of several materials: each element's region label (material.regions).
    sink.add<int32_t>("region", 1, ne, [&](unsigned char* dst) {
      for (size_t e = 0; e < ne; ++e) store(dst, e, int32_t(model.materialLabel[model.elementMaterial[e0 + e]]));
    });
  }
  if (!elementStress.empty()) sink.add<double>("element_stress", elementStress.data() + e0, ne);
  if (!elementStrain.empty()) sink.add<double>("element_strain", elementStrain.data() + e0, ne);
  x += "      </CellData>\n";
  x += "      <Points>\n";
  vectors("position", state.positions);
  x += "      </Points>\n";
  x += "      <Cells>\n";
  sink.add<int32_t>("connectivity", 1, pairs, [&](unsigned char* dst) {
    if (model.dim != 2) {
      for (uint32_t p = 0; p < pairs; ++p) store(dst, p, int32_t(model.elemVerts[p0 + p] - v0));
      return;
    }
    // 2D: each element's vertices in angular order about its rest centroid (rest offsets are
    // relative to it), which traces the element's outline.
    std::vector<std::pair<double, uint32_t>> ring;
    for (size_t e = 0; e < ne; ++e) {
      const uint32_t b = model.elemStart[e0 + e], end = model.elemStart[e0 + e + 1];
      ring.clear();
      for (uint32_t p = b; p < end; ++p) {
        const Vec3 r = model.restOffset(e0 + e, p);
        ring.emplace_back(std::atan2(r.y(), r.x()), p);
      }
      std::stable_sort(ring.begin(), ring.end(), [](const auto& a, const auto& c) { return a.first < c.first; });
      for (size_t k = 0; k < ring.size(); ++k) store(dst, b - p0 + k, int32_t(model.elemVerts[ring[k].second] - v0));
    }
  });
  sink.add<int32_t>("offsets", 1, ne, [&](unsigned char* dst) {
    for (size_t e = 0; e < ne; ++e) store(dst, e, int32_t(model.elemStart[e0 + e + 1] - p0));
  });
  sink.add<uint8_t>("types", 1, ne, [&](unsigned char* dst) {
    std::memset(dst, model.dim == 2 ? kVtkPolygon : kVtkConvexPointSet, ne);
  });
  x += "      </Cells>\n";
  x += "    </Piece>\n";
  x += "  </UnstructuredGrid>\n";
}

// ---- frames written in the background -------------------------------------------------

struct FrameFileWriter::Impl {
  std::mutex mutex;
  std::condition_variable changed;
  VtuBytes buffers[2];
  int fill = 0;                     // buffers[fill] is the caller's
  const VtuBytes* job = nullptr;    // the buffer being written, or none
  fs::path file;                    // where `job` goes
  bool stop = false;
  std::exception_ptr error;         // the first failed write
  std::thread thread;

  void loop() {
    std::unique_lock lock(mutex);
    for (;;) {
      changed.wait(lock, [&] { return job || stop; });
      if (!job) return;
      const VtuBytes* bytes = job;
      const fs::path target = file;
      lock.unlock();
      std::exception_ptr failed;
      try {
        writeVtu(target, *bytes);
      } catch (...) {
        failed = std::current_exception();
      }
      lock.lock();
      if (failed && !error) error = failed;
      job = nullptr;
      changed.notify_all();
    }
  }
  void waitIdle(std::unique_lock<std::mutex>& lock) {
    changed.wait(lock, [&] { return job == nullptr; });
  }
};

FrameFileWriter::FrameFileWriter() : impl_(std::make_unique<Impl>()) {
  impl_->thread = std::thread([this] { impl_->loop(); });
}

FrameFileWriter::~FrameFileWriter() {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stop = true;
  }
  impl_->changed.notify_all();
  impl_->thread.join();
}

VtuBytes& FrameFileWriter::buffer() { return impl_->buffers[impl_->fill]; }

void FrameFileWriter::submit(const fs::path& file) {
  std::unique_lock lock(impl_->mutex);
  impl_->waitIdle(lock);
  if (impl_->error) std::rethrow_exception(impl_->error);
  impl_->job = &impl_->buffers[impl_->fill];
  impl_->file = file;
  impl_->fill ^= 1;
  lock.unlock();
  impl_->changed.notify_all();
}

void FrameFileWriter::finish() {
  std::unique_lock lock(impl_->mutex);
  impl_->waitIdle(lock);
  if (impl_->error) std::rethrow_exception(impl_->error);
}

void writePvd(const fs::path& file, const std::vector<PvdFrame>& frames) {
  std::string out = "<?xml version=\"1.0\"?>\n";
  out += std::string("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"") + kByteOrder + "\">\n";
  out += "  <Collection>\n";
  for (const PvdFrame& f : frames) {
    out += "    <DataSet timestep=\"";
    appendNumber(out, f.time);
    out += "\" group=\"\" part=\"" + std::to_string(f.part) + "\"";
    if (!f.name.empty()) out += " name=\"" + xmlEscape(f.name) + "\"";
    out += " file=\"" + xmlEscape(f.file) + "\"/>\n";
  }
  out += "  </Collection>\n";
  out += "</VTKFile>\n";
  writeWholeFile(file, out);
}

// ---- metrics ----------------------------------------------------------------------

std::string MetricsCsv::header(size_t manipulators, bool bodyColumn, bool carving) {
  std::string h = std::string(bodyColumn ? "body," : "") +
                  "time,kinetic_energy,elastic_energy,gravity_energy,px,py,pz,Lx,Ly,Lz,max_stress,max_penetration,"
                  "max_contact_depth,min_element_det";
  auto forceColumns = [&](const std::string& p) {
    for (const char* c : {"fx", "fy", "fz", "tx", "ty", "tz"}) h += "," + p + c;
  };
  for (size_t k = 0; k < manipulators; ++k) forceColumns("m" + std::to_string(k) + "_");
  forceColumns("wall_");
  for (int w = 0; w < kWalls; ++w) forceColumns(std::string("wall_") + wallName(w) + "_");  // per wall (contacts.h)
  h += ",max_strain";  // after the forces: the columns before it kept their places when it came (issue 28)
  if (carving) h += ",removed_voxels,removed_volume,removed_mass";  // carving runs only (issue 30)
  return h;
}

std::string MetricsCsv::row(const std::string& body, const Metrics& m, size_t manipulators, bool forces,
                            bool carving) {
  return body + "," + row(m, manipulators, forces, carving);
}

std::string MetricsCsv::row(const Metrics& m, size_t manipulators, bool forces, bool carving) {
  const ContactForces& cf = m.contactForces;
  if (forces && cf.manipulators.size() != manipulators)
    throw std::invalid_argument("MetricsCsv::row: " + std::to_string(cf.manipulators.size()) +
                                " manipulators' forces for a header of " + std::to_string(manipulators));
  const double v[] = {m.time,
                      m.kineticEnergy,
                      m.elasticEnergy,
                      m.gravityEnergy,
                      m.linearMomentum.x(),
                      m.linearMomentum.y(),
                      m.linearMomentum.z(),
                      m.angularMomentum.x(),
                      m.angularMomentum.y(),
                      m.angularMomentum.z(),
                      m.maxStress,
                      m.maxPenetration,
                      m.maxContactDepth,
                      m.minElementDet};
  std::string out;
  for (size_t i = 0; i < std::size(v); ++i) {
    if (i) out += ',';
    appendNumber(out, v[i]);
  }
  auto appendForce = [&](const ContactForce& f) {
    for (int c = 0; c < 3; ++c) out += ',', appendNumber(out, f.force[c]);
    for (int c = 0; c < 3; ++c) out += ',', appendNumber(out, f.torque[c]);
  };
  if (!forces) {
    out.append(6 * (manipulators + 1 + kWalls), ',');
  } else {
    for (const ContactForce& f : cf.manipulators) appendForce(f);
    appendForce(cf.walls);
    for (const ContactForce& f : cf.wall) appendForce(f);
  }
  out += ',', appendNumber(out, m.maxStrain);
  if (carving)
    for (const double x : {double(m.removed.voxels), m.removed.volume, m.removed.mass}) out += ',', appendNumber(out, x);
  return out;
}

MetricsCsv::MetricsCsv(const fs::path& file, size_t manipulators, bool bodyColumn, bool carving)
    : path_(file), manipulators_(manipulators), bodyColumn_(bodyColumn), carving_(carving) {
  file_ = std::fopen(file.c_str(), "wb");
  if (!file_) throwWriteError(file, errno);
  std::fputs(header(manipulators, bodyColumn, carving).c_str(), file_);
  std::fputc('\n', file_);
}

MetricsCsv::~MetricsCsv() {
  if (file_) std::fclose(file_);
}

void MetricsCsv::append(const Metrics& m) {
  if (bodyColumn_) throw std::logic_error("MetricsCsv::append without a body in a file with a body column");
  writeLine(row(m, manipulators_, true, carving_));
}

void MetricsCsv::append(const std::string& body, const Metrics& m, bool forces) {
  if (!bodyColumn_) throw std::logic_error("MetricsCsv::append with a body in a file without a body column");
  writeLine(row(body, m, manipulators_, forces, carving_));
}

void MetricsCsv::writeLine(std::string line) {
  if (!file_) throw std::logic_error("MetricsCsv::append after close");
  line += '\n';
  if (std::fwrite(line.data(), 1, line.size(), file_) != line.size() && !err_) err_ = errno ? errno : EIO;
}

void MetricsCsv::close() {
  if (!file_) return;
  // ferror covers every earlier fwrite (err_ keeps the first one's reason); fclose reports the
  // final flush.
  errno = 0;
  const bool failed = std::ferror(file_) != 0 || err_ != 0;
  const bool closeFailed = std::fclose(file_) != 0;
  const int err = err_ ? err_ : errno;
  file_ = nullptr;
  if (failed || closeFailed) throwWriteError(path_, err);
}

// ---- output directory ---------------------------------------------------------------

namespace {
// A fresh, unused sibling name "<base>XXXXXX"; mkdtemp makes it unique and atomic.
fs::path makeUniqueDir(const std::string& base) {
  std::string tmpl = base + "XXXXXX";
  if (!::mkdtemp(tmpl.data())) return {};
  return tmpl;
}

// "<leaf>.tmp-": the temporary directories of `target` are "<leaf>.tmp-<pid>-XXXXXX".
std::string tempPrefix(const fs::path& target) { return target.filename().string() + ".tmp-"; }

// A run holds an flock on "<temp>/.lock" while it writes: a pid from another pid namespace
// (a container sharing the folder) may look dead here, its lock does not.
constexpr const char* kLockName = ".lock";

bool lockedByALiveRun(const fs::path& dir) {
  const int fd = ::open((dir / kLockName).c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool locked = ::flock(fd, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  ::close(fd);
  return locked;
}
}  // namespace

size_t removeStaleTemporaries(const fs::path& target) {
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  const std::string prefix = tempPrefix(target);
  std::error_code ec;
  std::vector<fs::path> stale;
  for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    // The owner's pid, then '-' and mkdtemp's six characters; anything else is not ours.
    const char* p = name.c_str() + prefix.size();
    long pid = 0;
    const auto r = std::from_chars(p, name.c_str() + name.size(), pid);
    if (r.ec != std::errc() || r.ptr == p || pid <= 0 || *r.ptr != '-' || std::strlen(r.ptr) != 7) continue;
    if (pid == long(::getpid())) continue;
    if (::kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue;  // alive (or not ours to ask about)
    std::error_code st;
    if (fs::is_directory(fs::symlink_status(it->path(), st)) && !lockedByALiveRun(it->path()))
      stale.push_back(it->path());
  }
  size_t removed = 0;
  for (const fs::path& p : stale) {
    std::error_code rm;
    fs::remove_all(p, rm);
    removed += rm ? 0 : 1;
  }
  return removed;
}

OutputDirectory::OutputDirectory(fs::path target, const std::string& marker) {
  if (marker.empty()) throw std::invalid_argument("OutputDirectory: marker must name a file of a previous result");
  target = target.lexically_normal();
  if (!target.has_filename()) target = target.parent_path();  // "out/x/" -> "out/x"
  const std::string leaf = target.filename().string();
  if (leaf.empty() || leaf == "." || leaf == "..")
    throw InputError(target.string() + ": cannot be used as an output directory (name the result directory itself)");
  target_ = target;

  std::error_code ec;
  const fs::file_status st = fs::status(target_, ec);
  if (fs::exists(st)) {
    if (!fs::is_directory(st)) throw InputError(target_.string() + ": exists and is not a directory");
    if (!fs::is_empty(target_, ec) && !fs::exists(target_ / marker, ec))
      throw InputError(target_.string() + ": exists and is not a previous result (no " + marker +
                       "); refusing to replace it");
  }

  const fs::path parent = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
  for (fs::path p = parent; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    createdParents_.push_back(p);
    if (p == p.parent_path()) break;
  }
  fs::create_directories(parent, ec);
  if (ec) {
    abort();
    if (ec == std::errc::not_a_directory || ec == std::errc::file_exists)
      throw InputError(parent.string() + ": cannot create: " + ec.message());
    throw IoError(parent.string() + ": cannot create: " + ec.message());
  }
  removeStaleTemporaries(target_);
  temp_ = makeUniqueDir((parent / (tempPrefix(target_) + std::to_string(::getpid()) + "-")).string());
  if (temp_.empty()) {
    const int err = errno;
    abort();
    throw IoError(target_.string() + ": cannot create a directory beside it: " + std::strerror(err));
  }
  lockFd_ = ::open((temp_ / kLockName).c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (lockFd_ < 0 || ::flock(lockFd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    abort();
    throw IoError((temp_ / kLockName).string() + ": cannot create: " + std::strerror(err));
  }
}

OutputDirectory::~OutputDirectory() {
  if (!finished_) abort();
}

void OutputDirectory::unlock() noexcept {
  if (lockFd_ < 0) return;
  ::unlink((temp_ / kLockName).c_str());
  ::close(lockFd_);  // releases the flock
  lockFd_ = -1;
}

void OutputDirectory::abort() noexcept {
  std::error_code ec;
  unlock();
  if (!temp_.empty()) fs::remove_all(temp_, ec);
  for (const fs::path& p : createdParents_) fs::remove(p, ec);  // only removes empty directories
  finished_ = true;
}

void OutputDirectory::commit() {
  if (finished_) throw std::logic_error("OutputDirectory::commit: already committed or aborted");
  unlock();  // the result holds no lock file
  std::error_code ec;
  fs::path old;
  if (fs::exists(fs::symlink_status(target_, ec))) {
    // Reserve a unique name, then free it for rename() (which also moves a symlink).
    old = makeUniqueDir(target_.string() + ".old-");
    if (old.empty() || ::rmdir(old.c_str()) != 0 || std::rename(target_.c_str(), old.c_str()) != 0)
      throw IoError("cannot move the previous " + target_.string() + " aside: " + std::strerror(errno));
  }
  if (std::rename(temp_.c_str(), target_.c_str()) != 0) {
    const int err = errno;
    if (!old.empty()) std::rename(old.c_str(), target_.c_str());  // put the previous result back
    throw IoError("cannot rename " + temp_.string() + " to " + target_.string() + ": " + std::strerror(err));
  }
  committed_ = finished_ = true;
  if (!old.empty()) fs::remove_all(old, ec);
}

}  // namespace gradel
