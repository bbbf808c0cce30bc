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
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <system_error>
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
  if constexpr (std::is_same_v<T, int64_t>) return "Int64";
  if constexpr (std::is_same_v<T, uint8_t>) return "UInt8";
}

// One <DataArray>. Binary form (VTK XML "binary", uncompressed): base64 of one stream holding
// a UInt32 byte count followed by the raw values in native byte order, which is how
// vtkXMLDataParser::ReadUncompressedData reads it back.
template <class T>
void appendDataArray(std::string& out, const char* name, int components, const std::vector<T>& values,
                     VtkEncoding encoding) {
  out += "        <DataArray type=\"";
  out += vtkTypeName<T>();
  out += "\"";
  if (name) out += std::string(" Name=\"") + name + "\"";
  if (components > 1) out += " NumberOfComponents=\"" + std::to_string(components) + "\"";
  out += encoding == VtkEncoding::Ascii ? " format=\"ascii\">\n" : " format=\"binary\">\n";
  if (encoding == VtkEncoding::Ascii) {
    for (size_t i = 0; i < values.size(); ++i) {
      appendNumber(out, values[i]);
      out += (i + 1) % size_t(std::max(components, 1)) == 0 || i + 1 == values.size() ? '\n' : ' ';
    }
  } else {
    const size_t bytes = values.size() * sizeof(T);
    if (bytes > UINT32_MAX) throw std::runtime_error("writeVtu: array larger than 4 GiB");
    std::vector<unsigned char> raw(sizeof(uint32_t) + bytes);
    const uint32_t header = uint32_t(bytes);
    std::memcpy(raw.data(), &header, sizeof header);
    if (bytes) std::memcpy(raw.data() + sizeof header, values.data(), bytes);
    appendBase64(out, raw.data(), raw.size());
    out += '\n';
  }
  out += "        </DataArray>\n";
}

[[noreturn]] void throwWriteError(const fs::path& file, int err) {
  throw IoError("cannot write " + file.string() + ": " + std::strerror(err ? err : EIO));
}

void writeWholeFile(const fs::path& file, const std::string& text) {
  std::FILE* f = std::fopen(file.c_str(), "wb");
  if (!f) throwWriteError(file, errno);
  errno = 0;
  const bool wrote = std::fwrite(text.data(), 1, text.size(), f) == text.size() && std::fflush(f) == 0;
  const int err = errno;
  if (std::fclose(f) != 0 || !wrote) throwWriteError(file, wrote ? errno : err);
}

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

  std::vector<double> points(3 * nv), velocity(3 * nv);
  for (size_t v = 0; v < nv; ++v)
    for (int c = 0; c < 3; ++c) {
      points[3 * v + c] = state.positions[v0 + v][c];
      velocity[3 * v + c] = state.velocities[v0 + v][c];
    }

  std::vector<int64_t> connectivity;
  connectivity.reserve(model.elemStart[body.elementEnd] - model.elemStart[e0]);
  std::vector<int64_t> offsets(ne);
  std::vector<uint8_t> types(ne, model.dim == 2 ? kVtkPolygon : kVtkConvexPointSet);
  std::vector<int64_t> elementId(ne);
  std::vector<std::pair<double, uint32_t>> ring;  // (angle, pair) of one 2D element
  for (size_t e = 0; e < ne; ++e) {
    const uint32_t b = model.elemStart[e0 + e], end = model.elemStart[e0 + e + 1];
    if (model.dim == 2) {
      // restOffsets are relative to the rest centroid, so their angles order the outline.
      ring.clear();
      for (uint32_t p = b; p < end; ++p)
        ring.emplace_back(std::atan2(model.restOffsets[p].y(), model.restOffsets[p].x()), p);
      std::stable_sort(ring.begin(), ring.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
      for (const auto& r : ring) connectivity.push_back(int64_t(model.elemVerts[r.second] - v0));
    } else {
      for (uint32_t p = b; p < end; ++p) connectivity.push_back(int64_t(model.elemVerts[p] - v0));
    }
    offsets[e] = int64_t(connectivity.size());
    elementId[e] = int64_t(e);
  }
  auto slice = [](const std::vector<Real>& all, size_t from, size_t n) {
    return all.empty() ? std::vector<double>() : std::vector<double>(all.begin() + from, all.begin() + from + n);
  };
  const std::vector<double> pointStress = slice(vertexStress, v0, nv), cellStress = slice(elementStress, e0, ne);
  const std::vector<double> pointStrain = slice(vertexStrain, v0, nv), cellStrain = slice(elementStrain, e0, ne);
  const std::vector<uint8_t> level(model.level.begin() + e0, model.level.begin() + e0 + ne);

  std::string out;
  out.reserve(96 * nv + 12 * connectivity.size() + 64 * ne + 1024);  // base64: 4 characters per 3 bytes
  out += "<?xml version=\"1.0\"?>\n";
  out += std::string("<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"") + kByteOrder + "\">\n";
  out += "  <UnstructuredGrid>\n";
  out += "    <Piece NumberOfPoints=\"" + std::to_string(nv) + "\" NumberOfCells=\"" + std::to_string(ne) + "\">\n";
  out += vertexStress.empty() ? "      <PointData Vectors=\"velocity\">\n"
                              : "      <PointData Scalars=\"stress\" Vectors=\"velocity\">\n";
  appendDataArray(out, "velocity", 3, velocity, encoding);
  if (!vertexStress.empty()) appendDataArray(out, "stress", 1, pointStress, encoding);
  if (!vertexStrain.empty()) appendDataArray(out, "strain", 1, pointStrain, encoding);
  out += "      </PointData>\n";
  out += "      <CellData Scalars=\"level\">\n";
  appendDataArray(out, "level", 1, level, encoding);
  appendDataArray(out, "element_id", 1, elementId, encoding);
  if (model.materials.size() > 1 && model.elementMaterial.size() == NE) {
    // A body of several materials: each element's region label (material.regions).
    std::vector<int64_t> region(ne);
    for (size_t e = 0; e < ne; ++e) region[e] = model.materialLabel[model.elementMaterial[e0 + e]];
    appendDataArray(out, "region", 1, region, encoding);
  }
  if (!elementStress.empty()) appendDataArray(out, "element_stress", 1, cellStress, encoding);
  if (!elementStrain.empty()) appendDataArray(out, "element_strain", 1, cellStrain, encoding);
  out += "      </CellData>\n";
  out += "      <Points>\n";
  appendDataArray(out, "position", 3, points, encoding);
  out += "      </Points>\n";
  out += "      <Cells>\n";
  appendDataArray(out, "connectivity", 1, connectivity, encoding);
  appendDataArray(out, "offsets", 1, offsets, encoding);
  appendDataArray(out, "types", 1, types, encoding);
  out += "      </Cells>\n";
  out += "    </Piece>\n";
  out += "  </UnstructuredGrid>\n";
  out += "</VTKFile>\n";
  writeWholeFile(file, out);
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
