// The Python module `gradel` (pybind11): build a body from a numpy array, a file or a shape,
// simulate it, and read the state as numpy arrays. Positions and velocities are views of the
// World's own memory (no copy; writable); results computed on demand (stress, surfaces, volumes)
// are moved into the array's owner instead of copied. See python/example.py and docs/io.md.
#include <pybind11/eval.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>

#include "gradel/carve_scene.h"
#include "gradel/divergence.h"
#include "gradel/io/volume_data_source.h"
#include "gradel/io/volume_file.h"
#include "gradel/isosurface.h"
#include "gradel/scene.h"
#include "gradel/settings_check.h"
#include "gradel/surface.h"

namespace py = pybind11;
using namespace gradel;

namespace {

// ---- arrays without copies -----------------------------------------------------------

py::array vec3Array(std::vector<Vec3>&& v) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 is three packed doubles");
  auto* owner = new std::vector<Vec3>(std::move(v));
  py::capsule base(owner, [](void* p) { delete static_cast<std::vector<Vec3>*>(p); });
  return py::array_t<double>({py::ssize_t(owner->size()), py::ssize_t(3)},
                             {py::ssize_t(sizeof(Vec3)), py::ssize_t(sizeof(double))}, owner->data()->data(), base);
}

py::array realArray(std::vector<Real>&& v) {
  auto* owner = new std::vector<Real>(std::move(v));
  py::capsule base(owner, [](void* p) { delete static_cast<std::vector<Real>*>(p); });
  return py::array_t<double>({py::ssize_t(owner->size())}, {py::ssize_t(sizeof(Real))}, owner->data(), base);
}

// The volume as a boolean array indexed [i, j, k] (x fastest in memory: Fortran order).
py::array volumeArray(std::shared_ptr<const VoxelVolume> v) {
  auto* owner = new std::shared_ptr<const VoxelVolume>(std::move(v));
  py::capsule base(owner, [](void* p) { delete static_cast<std::shared_ptr<const VoxelVolume>*>(p); });
  const VoxelVolume& vol = **owner;
  const py::ssize_t nx = vol.nx(), ny = vol.ny(), nz = vol.nz();
  // The bytes are 0 / 1, which numpy's bool reads as False / True. Read-only: the volume is shared.
  py::array a(py::dtype("bool"), {nx, ny, nz}, {py::ssize_t(1), nx, nx * ny}, vol.data().data(), base);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

// ---- bodies -----------------------------------------------------------------------------

/// A voxel volume ready to simulate, from an array, a file or a shape.
struct Body {
  std::shared_ptr<const VoxelVolume> volume;
  std::string name;
};

Body bodyFromArray(const py::array& input, Real voxelSize) {
  const py::array_t<bool, py::array::forcecast> a(input);  // any dtype: non-zero is filled
  if (a.ndim() != 2 && a.ndim() != 3)
    throw InputError("array: expected 2 or 3 dimensions, got " + std::to_string(a.ndim()));
  const int dim = int(a.ndim());
  std::array<py::ssize_t, 3> n{a.shape(0), a.shape(1), dim == 3 ? a.shape(2) : 1};
  for (py::ssize_t s : n)
    if (s < 1 || s > 4096)
      throw InputError("array: every size must be in [1, 4096], got shape " +
                       std::string(py::str(input.attr("shape"))));
  auto v = std::make_shared<VoxelVolume>(dim, int(n[0]), int(n[1]), int(n[2]), voxelSize);
  uint8_t* out = v->data().data();
  const bool* in = a.data();
  const auto st = a.strides();
  for (py::ssize_t k = 0; k < n[2]; ++k)
    for (py::ssize_t j = 0; j < n[1]; ++j)
      for (py::ssize_t i = 0; i < n[0]; ++i) {
        const py::ssize_t off = i * st[0] + j * st[1] + (dim == 3 ? k * st[2] : 0);
        out[v->index(int(i), int(j), int(k))] =
            *reinterpret_cast<const bool*>(reinterpret_cast<const char*>(in) + off) ? 1 : 0;
      }
  if (v->countFilled() == 0) throw InputError("array: the volume is empty (no true voxel)");
  return {v, "numpy array"};
}

io::VolumeFileSpec fileSpec(const std::string& path, std::optional<std::string> format, std::optional<double> threshold,
                            std::optional<std::pair<double, double>> range, int resolution,
                            std::optional<std::array<int64_t, 3>> dims, std::optional<std::string> type,
                            const std::string& endian, uint64_t headerBytes, int model, Real voxelSize, int dim) {
  io::VolumeFileSpec s;
  s.path = path;
  if (format) s.format = io::parseVolumeFormat(*format);
  s.voxelSize = voxelSize;
  s.dim = dim;
  if (threshold && range) throw InputError(path + ": give threshold or range, not both");
  s.grey.threshold = threshold;
  if (range) {
    if (!(range->first <= range->second)) throw InputError(path + ": range must be (lo, hi) with lo <= hi");
    s.grey.rangeLo = range->first;
    s.grey.rangeHi = range->second;
  }
  s.resolution = resolution;
  if (dims) s.raw.dims = *dims;
  if (type) s.raw.samples.type = io::parseScalarType(*type);
  if (endian != "little" && endian != "big") throw InputError(path + ": endian must be 'little' or 'big'");
  s.raw.samples.bigEndian = endian == "big";
  s.raw.headerBytes = headerBytes;
  s.model = model;
  const io::VolumeFormat f = s.format ? *s.format : io::volumeFormatFromPath(path);
  if (f == io::VolumeFormat::Raw && (!dims || !type)) throw InputError(path + ": a raw file needs dims and type");
  return s;
}

// ---- simulations ------------------------------------------------------------------------

Vec3 vec(const std::vector<double>& v, const char* what, int dim) {
  if (int(v.size()) != dim && v.size() != 3)
    throw InputError(std::string(what) + ": expected " + std::to_string(dim) + " numbers, got " +
                     std::to_string(v.size()));
  Vec3 out(0, 0, 0);
  for (size_t i = 0; i < v.size(); ++i) out[int(i)] = v[i];
  if (!out.allFinite()) throw InputError(std::string(what) + ": not finite");
  return out;
}


/// A built scene plus lazily built display surfaces.
/// Thread safety (python/README.md): every method that reads or changes the world holds `mutex`;
/// step / advance_to hold it for the whole call (with the GIL released), so a mutation from
/// another thread waits for the step to end, and concurrent step calls run one after the other
/// (no lost steps). The mutex is always taken with the GIL released (WorldLock), so a thread
/// waiting for it never blocks a stepping thread that briefly takes the GIL to check signals.
/// Scene-level changes (add_body, add_pin before the first step) edit `scene` and build it again
/// (buildScene, as a scene file); the replaced worlds are kept in `retired` so that views taken
/// before stay valid memory (they no longer follow the simulation).
struct Simulation {
  std::mutex mutex;
  Scene scene;
  BuiltScene built;
  bool stepped = false;  ///< A step was made: the bodies are fixed from now on.
  /// A carving event changed the bodies (carveLocked): they are fixed from now on too, since
  /// building the scene again would undo the carving (and a body cut in two has no scene entry).
  bool carved = false;
  std::vector<std::unique_ptr<BuiltScene>> retired;
  std::map<std::pair<size_t, SurfaceKind>, DisplaySurface> surfaces;  ///< Per (body, kind), built on first use.
  /// surface("embedded") of a body from a volume: its isosurface, built on first use (per body).
  std::map<size_t, EmbeddedMesh> isoEmbedded;
  /// The state buffers before each carving event: views taken before it keep valid memory.
  std::vector<State> carvedStates;

  World& world() { return *built.world; }
};

/// A carving call's `labels` (None: every label): distinct integers 1 .. 65535, sorted.
std::vector<uint16_t> carveLabelsArg(const char* call, const std::optional<std::vector<long long>>& labels) {
  std::vector<uint16_t> out;
  if (!labels) return out;
  if (labels->empty()) throw InputError(std::string(call) + ": labels: expected at least one region label (or None)");
  for (long long l : *labels) {
    if (l < 1 || l > 65535)
      throw InputError(std::string(call) + ": labels: " + std::to_string(l) + " is not a region label (1 .. 65535)");
    out.push_back(uint16_t(l));
  }
  std::sort(out.begin(), out.end());
  if (std::adjacent_find(out.begin(), out.end()) != out.end())
    throw InputError(std::string(call) + ": labels: a label is listed twice");
  return out;
}

/// A carving event (carve_scene.h) under the lock: the old state's buffers kept for the views taken
/// before, the cached surfaces dropped. Returns the voxels removed.
template <class F>
size_t carveLocked(Simulation& s, F&& carve) {
  State copy = s.world().state();
  s.carvedStates.push_back(std::move(s.world().state()));
  s.world().state() = std::move(copy);
  size_t removed = 0;
  for (const CarveEvent& e : carve()) removed += e.removedVoxels;
  if (removed) s.surfaces.clear(), s.isoEmbedded.clear(), s.carved = true;
  return removed;
}

std::unique_ptr<Simulation> makeSimulation(Scene scene) {
  auto s = std::make_unique<Simulation>();
  s->built = buildScene(scene);
  s->scene = std::move(scene);
  return s;
}

/// Builds `next` (the simulation's scene with a change) in place of the current world, keeping
/// the manipulators added from Python (at their pose now). The scene is replaced only when the
/// build succeeds. Caller holds the lock.
void rebuild(Simulation& s, Scene next) {
  BuiltScene built = buildScene(next);
  const World& old = s.world();
  for (size_t i = s.scene.manipulators.size(); i < old.manipulators().size(); ++i)
    built.world->addManipulator(old.manipulators()[i].settings, old.manipulators()[i].position);
  s.retired.push_back(std::make_unique<BuiltScene>(std::move(s.built)));
  s.built = std::move(built);
  s.scene = std::move(next);
  s.surfaces.clear();
  s.isoEmbedded.clear();
}

/// Python data (dicts, lists, numbers, numpy arrays) as JSON text for the scene reader.
std::string toJson(const py::handle& obj, const std::string& what) {
  try {
    static const py::object* toList = new py::object(py::eval("lambda o: o.tolist()"));  // lives as the module
    return py::module_::import("json").attr("dumps")(obj, py::arg("default") = *toList).cast<std::string>();
  } catch (py::error_already_set& e) {
    throw InputError(what + ": not expressible as a scene's JSON (" + std::string(py::str(e.value())) + ")");
  }
}

/// Parses `scene` (JSON text) with the scene reader under the name `what`, reporting a key path
/// that starts with `prefix` (the wrapper's own key, e.g. "bodies[0].") without it.
Scene parseFragment(const std::string& scene, const std::string& what, const std::string& prefix) {
  try {
    return parseScene(scene, what);
  } catch (const InputError& e) {
    if (e.file() != what || e.field().rfind(prefix, 0) != 0) throw;
    throw InputError(what, e.field().substr(prefix.size()), e.detail());
  }
}

/// A path from Python: a list of keyframes, each a dict {"t", "position", "velocity"} (the scene
/// file's) or a tuple (t, position) / (t, position, velocity); as JSON text.
py::list pathList(const py::object& path) {
  py::list keys;
  for (const py::handle& k : path) {
    if (py::isinstance<py::dict>(k)) {
      keys.append(k);
    } else {
      const py::tuple t = py::tuple(py::reinterpret_borrow<py::object>(k));
      if (t.size() != 2 && t.size() != 3)
        throw InputError("path: a keyframe is (t, position), (t, position, velocity) or a dict, got " +
                         std::string(py::str(k)));
      py::dict d;
      d["t"] = t[0];
      d["position"] = t[1];
      if (t.size() == 3) d["velocity"] = t[2];
      keys.append(d);
    }
  }
  return keys;
}

/// A scene from Python: a file's path (str or os.PathLike) read by loadScene, or a dict of the
/// same keys read by the same reader as JSON (messages "dict: KEY: ..."; relative files from the
/// working folder).
Scene readScene(const py::object& scene) {
  if (py::isinstance<py::dict>(scene)) return parseScene(toJson(scene, "dict"), "dict");
  std::string path;
  try {
    path = py::module_::import("os").attr("fspath")(scene).cast<std::string>();
  } catch (py::error_already_set&) {
    throw py::type_error("expected a scene file's path (str or pathlib.Path) or a dict, got " +
                         std::string(py::str(py::type::of(scene).attr("__name__"))));
  }
  return loadScene(path);
}

/// Stand-ins for the simulation's bodies in a scene fragment: what a pin is read against (its
/// body's lattice: voxel size and position; the number of bodies). The pieces of a body cut in
/// two (appended after the scene's bodies, carve_scene.h) stand in with their own lattice.
py::list bodyStandIns(const Scene& scene, const BuiltScene& built) {
  py::list bodies;
  auto add = [&](Real voxelSize, const Vec3& position) {
    py::dict d;
    d["shape"] = "box";
    d["size"] = 1;
    d["voxel_size"] = voxelSize;
    d["position"] = std::vector<double>{position.x(), position.y(), position.z()};
    bodies.append(d);
  };
  for (size_t i = 0; i < scene.numBodies(); ++i) add(scene.bodies[i].shape.voxelSize, scene.bodies[i].position);
  for (size_t i = scene.numBodies(); i < built.numBodies(); ++i)
    add(built.bodies[i].volume.voxelSize(), built.bodies[i].model->origin);
  return bodies;
}

/// A manipulator's axis: "x", "y", "z" (as a union primitive's) or a direction vector.
Vec3 axisOf(const py::object& axis, int dim) {
  if (py::isinstance<py::str>(axis)) {
    const std::string a = axis.cast<std::string>();
    if (a == "x") return Vec3(1, 0, 0);
    if (a == "y") return Vec3(0, 1, 0);
    if (a == "z") return Vec3(0, 0, 1);
    throw InputError("axis: unknown value '" + a + "' (expected \"x\", \"y\", \"z\" or a vector)");
  }
  return vec(axis.cast<std::vector<double>>(), "axis", dim);
}

/// Holds a Simulation's mutex; taken with the GIL released (see Simulation), then the GIL is back.
struct WorldLock {
  std::unique_lock<std::mutex> lock;
  explicit WorldLock(Simulation& s) {
    py::gil_scoped_release release;
    lock = std::unique_lock<std::mutex>(s.mutex);
  }
};

/// InputError unless every position and velocity is finite (NaN or inf written into the views).
void requireFiniteState(const World& w) {
  const State& st = w.state();
  for (size_t i = 0; i < st.positions.size(); ++i) {
    if (!st.positions[i].allFinite())
      throw InputError("positions: vertex " + std::to_string(i) +
                       " is not finite (NaN or inf written into positions?)");
    if (!st.velocities[i].allFinite())
      throw InputError("velocities: vertex " + std::to_string(i) +
                       " is not finite (NaN or inf written into velocities?)");
  }
}

std::string num(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}

constexpr double kMaxStepsPerCall = 1e9;  ///< advance_to refuses targets that need more steps.

/// Runs world steps while more() holds: the GIL released and the world locked for the whole
/// call; every 50 ms of wall time the GIL is taken briefly to honour Ctrl-C (KeyboardInterrupt;
/// the steps done so far are kept).
template <class More>
void runSteps(Simulation& s, More more) {
  py::gil_scoped_release release;
  std::lock_guard<std::mutex> lock(s.mutex);
  requireFiniteState(s.world());
  s.world().restartForceAverage();  // manipulator_force(): the average over this call's steps
  struct ForcesForThisCall {        // apply_force(): the forces act in this call's steps only
    World& w;
    ~ForcesForThisCall() { w.clearExternalForces(); }
  } forces{s.world()};
  auto last = std::chrono::steady_clock::now();
  while (more()) {
    s.world().step();
    s.stepped = true;
    const auto now = std::chrono::steady_clock::now();
    if (now - last > std::chrono::milliseconds(50)) {
      last = now;
      py::gil_scoped_acquire acquire;
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
  }
}

/// Copies an (N, 3) array into one of the world's per-vertex arrays, refusing NaN / inf.
void assignState(Simulation& s, std::vector<Vec3>& dst, const py::array_t<double, py::array::forcecast>& a,
                 const char* what) {
  if (a.ndim() != 2 || size_t(a.shape(0)) != dst.size() || a.shape(1) != 3)
    throw InputError(std::string(what) + ": expected shape (" + std::to_string(dst.size()) + ", 3)");
  auto r = a.unchecked<2>();
  std::vector<Vec3> v(dst.size());
  for (size_t i = 0; i < v.size(); ++i) {
    v[i] = Vec3(r(i, 0), r(i, 1), r(i, 2));
    if (!v[i].allFinite()) throw InputError(std::string(what) + ": row " + std::to_string(i) + " is not finite");
    if (s.scene.dim == 2 && v[i].z() != 0)
      throw InputError(std::string(what) + ": row " + std::to_string(i) + " has z != 0 in 2D");
  }
  WorldLock lock(s);
  dst = std::move(v);
}

// A view of one of the world's per-vertex vector arrays (positions, velocities), kept alive by
// the Simulation object that owns the world.
py::array stateView(py::object self, std::vector<Vec3>& v, size_t begin = 0, size_t end = size_t(-1)) {
  end = std::min(end, v.size());
  return py::array_t<double>({py::ssize_t(end - begin), py::ssize_t(3)},
                             {py::ssize_t(sizeof(Vec3)), py::ssize_t(sizeof(double))}, v[begin].data(), self);
}

const BodyRange& bodyRange(Simulation& s, size_t body) {
  if (body >= s.built.numBodies())
    throw py::index_error("no body " + std::to_string(body) + " (the scene has " + std::to_string(s.built.numBodies()) +
                          ")");
  return s.built.range(body);
}

py::dict metricsDict(Metrics x, bool finite) {
  if (!finite) {  // NaN spreads honestly: no min/max over NaN that hides it
    const Real nan = std::numeric_limits<Real>::quiet_NaN();
    x.kineticEnergy = x.elasticEnergy = x.gravityEnergy = x.maxStress = x.maxStrain = x.maxPenetration = x.minElementDet =
        nan;
  }
  py::dict d;
  d["time"] = x.time;
  d["kinetic_energy"] = x.kineticEnergy;
  d["elastic_energy"] = x.elasticEnergy;
  d["gravity_energy"] = x.gravityEnergy;
  d["linear_momentum"] = std::vector<double>{x.linearMomentum.x(), x.linearMomentum.y(), x.linearMomentum.z()};
  d["angular_momentum"] = std::vector<double>{x.angularMomentum.x(), x.angularMomentum.y(), x.angularMomentum.z()};
  d["max_stress"] = x.maxStress;  // [Pa] von Mises
  d["max_strain"] = x.maxStrain;  // [-]
  d["max_penetration"] = x.maxPenetration;
  d["min_element_det"] = x.minElementDet;
  // Carving since t = 0 (World::removedMaterial; docs/carving.md, "Feedback").
  d["removed_voxels"] = x.removed.voxels;
  d["removed_volume"] = x.removed.volume;  // [m^3]
  d["removed_mass"] = x.removed.mass;      // [kg]
  d["removed_momentum"] = std::vector<double>{x.removed.momentum.x(), x.removed.momentum.y(), x.removed.momentum.z()};
  return d;
}

}  // namespace

PYBIND11_MODULE(gradel, m) {
  m.doc() = "gradel: real-time elastic bodies from voxel volumes (Miyazaki et al. 2002 gradational layout)";
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);

  m.def(
      "load_volume",
      [](const std::string& path, std::optional<std::string> format, std::optional<double> threshold,
         std::optional<std::pair<double, double>> range, int resolution, std::optional<std::array<int64_t, 3>> dims,
         std::optional<std::string> type, const std::string& endian, uint64_t headerBytes, int model) {
        const io::VolumeFileSpec s =
            fileSpec(path, format, threshold, range, resolution, dims, type, endian, headerBytes, model, 0.01, 3);
        std::shared_ptr<const VoxelVolume> v;
        {
          py::gil_scoped_release release;
          v = std::make_shared<VoxelVolume>(io::readVolumeFile(s));
        }
        return volumeArray(std::move(v));
      },
      py::arg("path"), py::kw_only(), py::arg("format") = py::none(), py::arg("threshold") = py::none(),
      py::arg("range") = py::none(), py::arg("resolution") = 64, py::arg("dims") = py::none(),
      py::arg("type") = py::none(), py::arg("endian") = "little", py::arg("header_bytes") = 0, py::arg("model") = 0,
      "Reads a volume or mesh file (binvox, vox, nrrd, nifti, raw, obj, stl, ply) into a read-only boolean array "
      "[i, j, k] without copying it.");

  m.def(
      "check_scene", [](const py::object& scene) { (void)readScene(scene); }, py::arg("scene"),
      "Reads and checks a scene (a file's path, str or pathlib.Path, or a dict of its keys) with the scene "
      "reader, building nothing: ValueError (InputError) naming the key, e.g. 'dict: body.size: ...'. Referenced "
      "files must exist; they are read when the scene is built.");

  py::class_<Body>(m, "Body", "A binary voxel volume to simulate.")
      .def_static("from_array", &bodyFromArray, py::arg("voxels"), py::kw_only(), py::arg("voxel_size") = 0.01,
                  "From a 3D (or 2D) array indexed [i, j, k]; non-zero entries are filled. voxel_size in metres.")
      .def_static(
          "from_file",
          [](const std::string& path, std::optional<std::string> format, std::optional<double> threshold,
             std::optional<std::pair<double, double>> range, int resolution, std::optional<std::array<int64_t, 3>> dims,
             std::optional<std::string> type, const std::string& endian, uint64_t headerBytes, int model,
             Real voxelSize, int dim) {
            const io::VolumeFileSpec s = fileSpec(path, format, threshold, range, resolution, dims, type, endian,
                                                  headerBytes, model, voxelSize, dim);
            return Body{std::make_shared<VoxelVolume>(io::readVolumeFile(s)), path};
          },
          py::arg("path"), py::kw_only(), py::arg("format") = py::none(), py::arg("threshold") = py::none(),
          py::arg("range") = py::none(), py::arg("resolution") = 64, py::arg("dims") = py::none(),
          py::arg("type") = py::none(), py::arg("endian") = "little", py::arg("header_bytes") = 0, py::arg("model") = 0,
          py::arg("voxel_size") = 0.01, py::arg("dim") = 3,
          "From a file; the options are those of a scene's body.source (docs/scenes.md).")
      .def_static(
          "from_shape",
          [](const std::string& shape, int size, int dim, Real voxelSize) {
            return Body{std::make_shared<VoxelVolume>(rasterize(presetShape(shape, size, dim, voxelSize))), shape};
          },
          py::arg("shape"), py::arg("size"), py::kw_only(), py::arg("dim") = 3, py::arg("voxel_size") = 0.01,
          "A preset shape ('box', 'sphere', 'cylinder') inscribed in a size^dim grid.")
      .def_property_readonly(
          "voxels", [](const Body& b) { return volumeArray(b.volume); }, "Read-only boolean view [i, j, k].")
      .def_property_readonly("dim", [](const Body& b) { return b.volume->dim(); })
      .def_property_readonly("voxel_size", [](const Body& b) { return b.volume->voxelSize(); })
      .def_property_readonly("filled", [](const Body& b) { return b.volume->countFilled(); })
      .def("__repr__", [](const Body& b) {
        const auto& d = b.volume->dims();
        return "<gradel.Body " + b.name + " " + std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" +
               std::to_string(d[2]) + ", " + std::to_string(b.volume->countFilled()) + " voxels>";
      });

  py::class_<Simulation>(m, "Simulation", "A body built into a gradational layout and simulated (World).")
      .def(py::init([](const Body& body, const std::string& layout, const std::string& scaling, Real youngsModulus,
                       Real density, Real k, const std::string& integrator, std::optional<Real> dt, Real dtFraction,
                       Real damping, std::vector<double> gravity, int threads, std::vector<double> position,
                       std::vector<double> velocity, std::optional<std::vector<double>> domainMin,
                       std::optional<std::vector<double>> domainMax, Real restitution, Real friction,
                       Real poissonRatio) {
             Scene s;
             s.name = "python";
             s.dim = body.volume->dim();
             s.bodies[0].source = std::make_shared<io::VolumeDataSource>(body.volume, body.name);
             s.bodies[0].shape.voxelSize = body.volume->voxelSize();  // the body's lattice (pins)
             s.bodies[0].layout = parseLayoutKind(layout);
             s.bodies[0].material.scaling = parseScaling(scaling);
             s.bodies[0].material.youngsModulus = youngsModulus;
             s.bodies[0].material.density = density;
             s.bodies[0].material.paperK = k;
             s.bodies[0].material.poissonRatio = poissonRatio;
             s.bodies[0].position = vec(position, "position", s.dim);
             s.bodies[0].velocity = vec(velocity, "velocity", s.dim);
             s.simulation.integrator = parseIntegratorKind(integrator);
             if (dt && !(*dt > 0)) throw InputError("dt: must be > 0 (or None for auto)");
             s.simulation.dt = dt.value_or(0);
             s.simulation.dtFraction = dtFraction;
             s.simulation.damping = damping;
             s.simulation.gravity = vec(gravity, "gravity", s.dim);
             s.simulation.threads = threads;
             validate(s.bodies[0].material);
             validate(s.simulation);
             if (domainMin || domainMax) {
               if (!domainMin || !domainMax) throw InputError("domain: give both domain_min and domain_max");
               s.domain.enabled = true;
               s.domain.min = vec(*domainMin, "domain_min", s.dim);
               s.domain.max = vec(*domainMax, "domain_max", s.dim);  // 2D: z range set by buildScene
               s.domain.restitution = restitution;
               s.domain.friction = friction;
               validate(s.domain, s.dim);
             }
             return makeSimulation(std::move(s));
           }),
           py::arg("body"), py::kw_only(), py::arg("layout") = "gradational", py::arg("scaling") = "consistent",
           py::arg("youngs_modulus") = MaterialSettings{}.youngsModulus,
           py::arg("density") = MaterialSettings{}.density, py::arg("k") = MaterialSettings{}.paperK,
           py::arg("integrator") = "symplectic", py::arg("dt") = py::none(),
           py::arg("dt_fraction") = SimulationSettings{}.dtFraction, py::arg("damping") = SimulationSettings{}.damping,
           py::arg("gravity") = std::vector<double>{0, -9.81, 0}, py::arg("threads") = 1,
           py::arg("position") = std::vector<double>{0, 0, 0}, py::arg("velocity") = std::vector<double>{0, 0, 0},
           py::arg("domain_min") = py::none(), py::arg("domain_max") = py::none(),
           py::arg("restitution") = DomainSettings{}.restitution, py::arg("friction") = DomainSettings{}.friction,
           py::arg("poisson_ratio") = MaterialSettings{}.poissonRatio,
           "Builds layout, rest model and world. Units: SI (m, s, kg, Pa). Material, layout and integrator are fixed "
           "for the simulation's life (the rest model is immutable): make a new Simulation to change them.")
      .def_static(
          "from_scene", [](const py::object& scene) { return makeSimulation(readScene(scene)); },
          py::arg("scene"),
          "Builds the simulation of a scene (docs/scenes.md), manipulators, pins and all: a JSON file's path (str "
          "or pathlib.Path) or a dict of the same keys, read and checked by the same reader (ValueError naming the "
          "key, e.g. 'dict: body.size: ...').")
      .def(
          "add_body",
          [](Simulation& s, const Body* volume, py::kwargs kw) {
            static const std::vector<std::string> kKeys = {
                "shape", "size", "grid", "primitives", "source", "voxel_size", "layout", "position", "velocity",
                "name", "material", "scaling", "youngs_modulus", "density", "k", "poisson_ratio", "regions"};
            py::dict entry, material;
            for (const auto& [key, value] : kw) {
              const std::string k = key.cast<std::string>();
              if (std::find(kKeys.begin(), kKeys.end(), k) == kKeys.end())
                throw py::type_error("add_body() got an unexpected keyword argument '" + k + "'");
              if (value.is_none()) continue;
              if (k == "material") {
                for (const auto& [mk, mv] : value.cast<py::dict>()) material[mk] = mv;
              } else if (k == "scaling" || k == "youngs_modulus" || k == "density" || k == "k" || k == "poisson_ratio" ||
                         k == "regions") {
                material[py::str(k)] = value;
              } else {
                entry[py::str(k)] = value;
              }
            }
            if (volume) {
              for (const char* k : {"shape", "size", "grid", "primitives", "source", "voxel_size"})
                if (entry.contains(k))
                  throw InputError(std::string("add_body: ") + k + ": not allowed with a Body (it has its voxels)");
              if (volume->volume->dim() != s.scene.dim)
                throw InputError("add_body: body: a " + std::to_string(volume->volume->dim()) + "D Body in a " +
                                 std::to_string(s.scene.dim) + "D simulation");
              entry["shape"] = "box";  // a stand-in for the reader; the Body's voxels replace it
              entry["size"] = 1;
              entry["voxel_size"] = volume->volume->voxelSize();
            }
            if (material.size() > 0) entry["material"] = material;
            py::dict scene;
            scene["dim"] = s.scene.dim;
            scene["bodies"] = py::make_tuple(entry);
            Scene parsed = parseFragment(toJson(scene, "add_body"), "add_body", "bodies[0].");
            BodySettings b = std::move(parsed.bodies[0]);
            if (volume) {
              b.source = std::make_shared<io::VolumeDataSource>(volume->volume, volume->name);
              b.sizeKey = "add_body";
            }
            WorldLock lock(s);
            if (s.stepped)
              throw InputError("add_body: bodies are added before the first step (the simulation is at t = " +
                               num(s.world().time()) + " s); build a new Simulation");
            if (s.carved)
              throw InputError("add_body: bodies are added before the first carving event (building the scene "
                               "again would undo it); build a new Simulation");
            const size_t index = s.scene.numBodies();
            if (!entry.contains("name")) b.name = "body" + std::to_string(index);
            for (size_t i = 0; i < index; ++i)
              if (s.scene.bodies[i].name == b.name)
                throw InputError("add_body: name: \"" + b.name + "\" is the name of body " + std::to_string(i) +
                                 " too (expected a name of its own)");
            Scene next = s.scene;
            next.bodies.push_back(std::move(b));
            rebuild(s, std::move(next));
            return index;
          },
          py::arg("body") = py::none(),
          "Adds a body before the first step and returns its index: a Body (its voxels), or the keys of a scene "
          "file's bodies[i] as keyword arguments: shape, size (or grid, primitives), source (a dict as body.source), "
          "voxel_size, layout, position [m], velocity [m/s], name, material (a dict: scaling, youngs_modulus, "
          "density, k, regions) or those material keys directly. Checked by the scene reader (ValueError naming "
          "the key). The world is built again: views of positions taken before no longer follow it. Bodies in 3D "
          "collide with each other (body_contact). ValueError after the first step.")
      .def(
          "add_pin",
          [](Simulation& s, std::optional<std::vector<double>> min, std::optional<std::vector<double>> max,
             std::optional<py::array> mask, std::optional<py::list> boxes, std::optional<std::vector<int>> offset,
             size_t body, std::optional<py::object> path) {
            py::dict pin;
            if (min) pin["min"] = *min;
            if (max) pin["max"] = *max;
            if (mask || boxes || offset) {
              py::dict m;
              py::list bs;
              if (boxes)
                for (const py::handle& b : *boxes) {
                  const py::tuple t = py::tuple(py::reinterpret_borrow<py::object>(b));
                  if (t.size() != 2) throw InputError("add_pin: boxes: each box is (min index, max index)");
                  py::dict d;
                  d["min"] = t[0];
                  d["max"] = t[1];
                  bs.append(d);
                }
              if (mask && bs.size() == 0) {  // a stand-in for the reader; the array replaces it
                py::dict d;
                d["min"] = std::vector<int>{0, 0, 0};
                d["max"] = std::vector<int>{0, 0, 0};
                bs.append(d);
              }
              m["boxes"] = bs;
              if (offset) m["offset"] = *offset;
              pin["mask"] = m;
            }
            pin["body"] = body;
            if (path) pin["path"] = pathList(*path);
            py::dict scene;
            scene["dim"] = s.scene.dim;
            scene["bodies"] = bodyStandIns(s.scene, s.built);
            scene["pins"] = py::make_tuple(pin);
            Scene parsed = parseFragment(toJson(scene, "add_pin"), "add_pin", "pins[0].");
            PinSettings p = std::move(parsed.pins.at(0));
            if (mask) {
              auto pm = std::make_shared<PinMask>(*p.mask);
              if (!boxes) pm->boxes.clear();
              Body m = bodyFromArray(*mask, pm->voxelSize);
              pm->volume = m.volume;
              p.mask = pm;
            }
            WorldLock lock(s);
            Scene next = s.scene;
            next.pins.push_back(p);
            const std::string key = "pins[" + std::to_string(next.pins.size() - 1) + "]";
            try {
              if (!s.stepped && !s.carved) {
                rebuild(s, std::move(next));
              } else {  // an anchor made while running: the live world takes it (its solvers refactor)
                s.world().setPins(next.pins);
                s.scene = std::move(next);
              }
            } catch (const InputError& e) {  // an error at "pins[i]..." of this pin: at "add_pin: ..."
              if (!e.file().empty()) throw;
              if (e.field() == key) throw InputError("add_pin", "", e.detail());
              if (e.field().rfind(key + ".", 0) == 0)
                throw InputError("add_pin", e.field().substr(key.size() + 1), e.detail());
              throw;
            }
            return s.scene.pins.size() - 1;
          },
          py::arg("min") = py::none(), py::arg("max") = py::none(), py::kw_only(), py::arg("mask") = py::none(),
          py::arg("boxes") = py::none(), py::arg("offset") = py::none(), py::arg("body") = 0,
          py::arg("path") = py::none(),
          "Pins (anchors) vertices of body `body` and returns the pin's index (scene key pins[i], pins.h): every "
          "vertex in the box [min, max] [m] (world, at rest), or every corner of a filled voxel of `mask` (a boolean "
          "array [i, j, k] on the body's lattice, from voxel `offset`) and of `boxes` ((min index, max index), "
          "inclusive). `path`: keyframes (t, offset [m]) or (t, offset, velocity) or dicts {t, position, velocity}: "
          "the pinned vertices' offset from rest over time (a moving target); none: held at rest. Before the first "
          "step the world is built again (views taken before no longer follow it); after, the live world takes it. "
          "ValueError when it holds no vertex.")
      .def(
          "carve_sphere",
          [](Simulation& s, const std::vector<double>& center, double radius, std::optional<std::vector<long long>> labels) {
            const std::vector<uint16_t> only = carveLabelsArg("carve_sphere", labels);
            if (center.size() != 3) throw InputError("carve_sphere: center: expected 3 numbers [m]");
            if (!(radius > 0) || !std::isfinite(radius)) throw InputError("carve_sphere: radius: expected a positive number [m]");
            const Vec3 c(center[0], center[1], center[2]);
            if (!c.allFinite()) throw InputError("carve_sphere: center: not finite");
            WorldLock lock(s);
            return carveLocked(s, [&] { return carveSceneSweep(s.built, c, c, radius, 0, only); });
          },
          py::arg("center"), py::arg("radius"), py::arg("labels") = py::none(),
          "Removes from every body the voxels whose centres lie within `radius` [m] of `center` [m] in the deformed "
          "configuration (docs/carving.md): the body is laid out again, surviving vertices keep their positions and "
          "velocities. Returns the number of voxels removed. Views of positions and velocities taken before no "
          "longer follow the world. A body is never emptied (removing every voxel of it does nothing). `labels`: "
          "only voxels of these region labels (a selective tool; None: every label).")
      .def(
          "carve_cylinder",
          [](Simulation& s, const std::vector<double>& center, const std::vector<double>& axis, double radius,
             double halfLength, std::optional<std::vector<long long>> labels) {
            const std::vector<uint16_t> only = carveLabelsArg("carve_cylinder", labels);
            if (center.size() != 3) throw InputError("carve_cylinder: center: expected 3 numbers [m]");
            if (axis.size() != 3) throw InputError("carve_cylinder: axis: expected 3 numbers");
            if (!(radius > 0) || !std::isfinite(radius))
              throw InputError("carve_cylinder: radius: expected a positive number [m]");
            if (!(halfLength > 0) || !std::isfinite(halfLength))
              throw InputError("carve_cylinder: half_length: expected a positive number [m]");
            const Vec3 c(center[0], center[1], center[2]), a(axis[0], axis[1], axis[2]);
            if (!c.allFinite()) throw InputError("carve_cylinder: center: not finite");
            if (!a.allFinite() || !(a.norm() > 0)) throw InputError("carve_cylinder: axis: expected a non-zero finite vector");
            WorldLock lock(s);
            return carveLocked(s, [&] { return carveSceneCylinderSweep(s.built, c, c, a.normalized(), radius, halfLength, 0, only); });
          },
          py::arg("center"), py::arg("axis"), py::arg("radius"), py::arg("half_length"), py::arg("labels") = py::none(),
          "Removes from every body the voxels whose centres lie in the solid cylinder of `radius` [m] and half "
          "length `half_length` [m] (flat caps) about `center` [m] along `axis` (any length, normalised), in the "
          "deformed configuration (docs/carving.md): a rod's or a core drill's bore. As carve_sphere otherwise "
          "(`labels` too); returns the number of voxels removed.")
      .def(
          "cut",
          [](Simulation& s, const std::vector<double>& center, const std::vector<std::vector<double>>& axes,
             const std::vector<double>& halfExtents, std::optional<std::vector<double>> to) {
            auto vec3 = [](const std::vector<double>& v, const char* key) {
              if (v.size() != 3) throw InputError(std::string("cut: ") + key + ": expected 3 numbers");
              const Vec3 x(v[0], v[1], v[2]);
              if (!x.allFinite()) throw InputError(std::string("cut: ") + key + ": not finite");
              return x;
            };
            if (s.scene.dim != 3) throw InputError("cut: a blade cuts 3D bodies only");
            const Vec3 c = vec3(center, "center");
            if (axes.size() != 2) throw InputError("cut: axes: expected two directions of 3 numbers");
            const Vec3 u = vec3(axes[0], "axes[0]"), w = vec3(axes[1], "axes[1]");
            if (!(u.norm() > 0) || !(w.norm() > 0)) throw InputError("cut: axes: expected non-zero directions");
            if (std::abs(u.normalized().dot(w.normalized())) > 1e-6)
              throw InputError("cut: axes: the two directions are not perpendicular (the blade is a rectangle)");
            if (halfExtents.size() != 2 || !(halfExtents[0] > 0) || !(halfExtents[1] > 0) ||
                !std::isfinite(halfExtents[0]) || !std::isfinite(halfExtents[1]))
              throw InputError("cut: half_extents: expected two lengths > 0 [m]");
            const BladeSweep blade{c, to ? vec3(*to, "to") : c, u, w, halfExtents[0], halfExtents[1]};
            WorldLock lock(s);
            return carveLocked(s, [&] { return carveSceneBlade(s.built, blade); });
          },
          py::arg("center"), py::arg("axes"), py::arg("half_extents"), py::arg("to") = py::none(),
          "A blade's cut (docs/carving.md, \"The blade\"): the rectangle about `center` [m] with half extents "
          "`half_extents` [m] along the two perpendicular `axes`, parked or moved to `to` [m] without turning, "
          "removes its one-voxel kerf from every body. A body cut in two becomes two bodies (num_bodies, "
          "body_names: the larger keeps its name, the other is '<name>-2'), which collide. Returns the voxels removed.")
      .def(
          "remove_voxels",
          [](Simulation& s, size_t body, const py::array& maskArray) {
            const py::array_t<bool, py::array::forcecast> a(maskArray);
            WorldLock lock(s);
            bodyRange(s, body);
            const VoxelVolume& v = s.built.bodies[body].volume;
            const int dim = v.dim();
            if (a.ndim() != dim || a.shape(0) != v.nx() || a.shape(1) != v.ny() || (dim == 3 && a.shape(2) != v.nz()))
              throw InputError("remove_voxels: mask: expected a boolean array of the body's grid shape (" +
                               std::to_string(v.nx()) + ", " + std::to_string(v.ny()) +
                               (dim == 3 ? ", " + std::to_string(v.nz()) : std::string()) + ")");
            std::vector<uint8_t> mask(v.size(), 0);
            const auto st = a.strides();
            const char* in = reinterpret_cast<const char*>(a.data());
            for (int k = 0; k < v.nz(); ++k)
              for (int j = 0; j < v.ny(); ++j)
                for (int i = 0; i < v.nx(); ++i)
                  mask[v.index(i, j, k)] =
                      *reinterpret_cast<const bool*>(in + i * st[0] + j * st[1] + (dim == 3 ? k * st[2] : 0)) ? 1 : 0;
            return carveLocked(s, [&] { return std::vector<CarveEvent>{carveSceneBody(s.built, body, mask)}; });
          },
          py::arg("body"), py::arg("mask"),
          "Removes the voxels of body `body` where `mask` (a boolean array [i, j, k] of the body's grid) is true "
          "(docs/carving.md) and returns how many were removed; as carve_sphere otherwise.")
      .def(
          "apply_force",
          [](Simulation& s, const py::array_t<int64_t, py::array::c_style | py::array::forcecast>& vertices,
             const py::array_t<double, py::array::c_style | py::array::forcecast>& forces, std::optional<size_t> body) {
            if (vertices.ndim() > 1) throw InputError("vertex_indices: expected a 1D array of vertex indices");
            const py::ssize_t n = vertices.ndim() == 0 ? 1 : vertices.shape(0);
            const bool one = forces.ndim() == 1;
            if (!(one && forces.shape(0) == 3) && !(forces.ndim() == 2 && forces.shape(0) == n && forces.shape(1) == 3))
              throw InputError("forces: expected shape (3,) or (" + std::to_string(n) + ", 3) [N]");
            WorldLock lock(s);
            size_t begin = 0, end = s.world().model().numVertices();
            if (body) {
              const BodyRange& r = bodyRange(s, *body);
              begin = r.vertexBegin, end = r.vertexEnd;
            }
            std::vector<uint32_t> ids(static_cast<size_t>(n));
            std::vector<Vec3> f(static_cast<size_t>(n));
            const int64_t* vi = vertices.data();
            for (py::ssize_t k = 0; k < n; ++k) {
              const int64_t v = vi[k];
              if (v < 0 || size_t(v) >= end - begin)
                throw py::index_error("vertex_indices: " + std::to_string(v) + " is not a vertex" +
                                      (body ? " of body " + std::to_string(*body) : std::string()) + " (expected 0.." +
                                      std::to_string(end - begin - 1) + ")");
              ids[size_t(k)] = uint32_t(begin + size_t(v));
              const double* fr = forces.data() + (one ? 0 : 3 * k);
              f[size_t(k)] = Vec3(fr[0], fr[1], fr[2]);  // non-finite: addExternalForces says which entry
            }
            s.world().addExternalForces(ids, f);
          },
          py::arg("vertex_indices"), py::arg("forces"), py::kw_only(), py::arg("body") = py::none(),
          "External forces [N] on vertices (PyBullet's applyExternalForce): forces (3,) for every listed vertex or "
          "(n, 3), one per vertex, added to those applied before; they act in every step of the next step() or "
          "advance_to() call, then are cleared. Indices are rows of positions, or of body_positions(body) with "
          "body=. Every integrator applies them as the impulse F dt at the start of a step (external_force.h): a "
          "force F on a free body for a time T changes its momentum by F T. Pinned vertices ignore them.")
      .def_property_readonly(
          "external_impulse",
          [](Simulation& s) {
            WorldLock lock(s);
            const Vec3& j = s.world().externalImpulse();
            return std::vector<double>{j.x(), j.y(), j.z()};
          },
          "[N s] the impulse apply_force() gave the bodies since t = 0 (their momentum is conserved up to it).")
      .def_property_readonly(
          "external_work",
          [](Simulation& s) {
            WorldLock lock(s);
            return s.world().externalWork();
          },
          "[J] the energy apply_force() gave the bodies since t = 0.")
      .def_property_readonly(
          "num_pins", [](Simulation& s) { return s.scene.pins.size(); }, "Pins of the scene and add_pin().")
      .def_property_readonly(
          "pinned_vertices",
          [](Simulation& s) {
            WorldLock lock(s);
            return std::vector<uint32_t>(s.world().pinned().vertices);
          },
          "Rows of positions held by a pin (ascending).")
      .def(
          "add_manipulator",
          [](Simulation& s, const std::string& type, Real radius, std::vector<double> position, Real halfLength,
             const py::object& axis, Real restitution, Real friction, std::optional<py::object> path) {
            ManipulatorSettings mp;
            mp.shape = parseManipulatorShape(type);
            if (mp.shape == ManipulatorShape::Blade)
              throw InputError("type: a 'blade' is set in the scene's manipulators (its \"axes\" and \"half_extents\")");
            if ((mp.shape == ManipulatorShape::Circle) != (s.scene.dim == 2))
              throw InputError("type: '" + type + "' does not fit a " + std::to_string(s.scene.dim) + "D body");
            if (!(radius > 0)) throw InputError("radius: must be > 0 [m]");
            mp.radius = radius;
            mp.halfLength = halfLength;
            mp.axis = axisOf(axis, s.scene.dim);
            if (!(mp.axis.norm() > 0)) throw InputError("axis: must be non-zero");
            mp.restitution = restitution;
            mp.friction = friction;
            validate(mp);
            if (path) {  // the scene reader's path, on a stand-in manipulator
              py::dict m, scene;
              m["type"] = s.scene.dim == 3 ? "sphere" : "circle";
              m["path"] = pathList(*path);
              scene["dim"] = s.scene.dim;
              scene["bodies"] = bodyStandIns(s.scene, s.built);
              scene["manipulators"] = py::make_tuple(m);
              mp.path = parseFragment(toJson(scene, "add_manipulator"), "add_manipulator", "manipulators[0].")
                            .manipulators.at(0)
                            .path;
            }
            const Vec3 at = vec(position, "position", s.scene.dim);
            WorldLock lock(s);
            return s.world().addManipulator(std::move(mp), at);
          },
          py::arg("type") = "sphere", py::kw_only(), py::arg("radius") = 0.02,
          py::arg("position") = std::vector<double>{0, 0, 0}, py::arg("half_length") = 0.05,
          py::arg("axis") = "z", py::arg("restitution") = 1.0, py::arg("friction") = 0.0,
          py::arg("path") = py::none(),
          "Adds a kinematic manipulator ('sphere', 'cylinder'; 'circle' in 2D); returns its index. axis: 'x', 'y', "
          "'z' or a vector (cylinder). path: keyframes (t, position) or (t, position, velocity) or dicts {t, "
          "position, velocity} as a scene's manipulators[i].path: it moves along it (position is then ignored); "
          "none: it stays at `position` until move_manipulator().")
      .def(
          "move_manipulator",
          [](Simulation& s, size_t i, std::vector<double> position, std::vector<double> velocity) {
            const Vec3 p = vec(position, "position", s.scene.dim), v = vec(velocity, "velocity", s.scene.dim);
            WorldLock lock(s);
            if (i >= s.world().manipulators().size()) throw py::index_error("no manipulator " + std::to_string(i));
            s.world().setManipulatorPose(i, p, v);
          },
          py::arg("index"), py::arg("position"), py::arg("velocity") = std::vector<double>{0, 0, 0},
          "Sets a manipulator's centre [m] and velocity [m/s]; the next step sweeps it from its last pose.")
      .def(
          "manipulator_force",
          [](Simulation& s, size_t i, bool average) {
            WorldLock lock(s);
            if (i >= s.world().manipulators().size()) throw py::index_error("no manipulator " + std::to_string(i));
            const ContactForce f = average ? s.world().averageContactForces().manipulators[i]
                                           : s.world().stepContactForces().manipulators[i];
            return py::make_tuple(std::vector<double>{f.force.x(), f.force.y(), f.force.z()},
                                  std::vector<double>{f.torque.x(), f.torque.y(), f.torque.z()});
          },
          py::arg("index"), py::kw_only(), py::arg("average") = true,
          "(force [N], torque [N m] about its centre) that the body exerts on manipulator `index`: averaged over "
          "the steps of the last step()/advance_to() call (average=True), or of the last step alone.")
      .def(
          "wall_force",
          [](Simulation& s, const std::string& wall, bool average) {
            int w = -1;  // all walls
            for (int k = 0; k < kWalls; ++k)
              if (wall == wallName(k)) w = k;
            if (w < 0 && wall != "all")
              throw py::value_error("unknown wall '" + wall + "' (expected all, xmin, xmax, ymin, ymax, zmin or zmax)");
            WorldLock lock(s);
            const ContactForces fs = average ? s.world().averageContactForces() : s.world().stepContactForces();
            const ContactForce f = w < 0 ? fs.walls : fs.wall[size_t(w)];
            return py::make_tuple(std::vector<double>{f.force.x(), f.force.y(), f.force.z()},
                                  std::vector<double>{f.torque.x(), f.torque.y(), f.torque.z()});
          },
          py::arg("wall") = "all", py::kw_only(), py::arg("average") = true,
          "(force [N], torque [N m] about the origin) that the body exerts on the walls together (wall='all') or "
          "on one wall of the domain box: 'xmin', 'xmax', 'ymin' (the floor under gravity -y), 'ymax', 'zmin', "
          "'zmax' (as manipulator_force).")
      .def_property_readonly("manipulator_positions",
                             [](Simulation& s) {
                               WorldLock lock(s);
                               std::vector<Vec3> p;
                               for (const Manipulator& mp : s.world().manipulators()) p.push_back(mp.position);
                               return vec3Array(std::move(p));
                             })
      .def(
          "step",
          [](Simulation& s, long n) {
            if (n < 0) throw InputError("n: must be >= 0 (got " + std::to_string(n) + ")");
            long done = 0;
            runSteps(s, [&] { return done++ < n; });
          },
          py::arg("n") = 1,
          "Advances n time steps of dt. Holds the world for the whole call (other threads' calls wait); Ctrl-C "
          "raises KeyboardInterrupt between steps.")
      .def(
          "advance_to",
          [](Simulation& s, Real t, double maxSteps) {
            if (!std::isfinite(t)) throw InputError("t: must be a finite time [s] (got " + num(t) + ")");
            runSteps(s, [&, checked = false]() mutable {
              World& w = s.world();
              if (!checked) {  // under the lock: time and dt are those this call will step from
                checked = true;
                const double steps = std::ceil((t - w.time()) / w.dt() - 0.5);
                if (steps > maxSteps) {
                  py::gil_scoped_acquire acquire;
                  throw InputError("t: advancing from " + num(w.time()) + " s to " + num(t) + " s takes about " +
                                   num(steps) + " steps of dt = " + num(w.dt()) +
                                   " s, more than max_steps = " + num(maxSteps) + " (pass max_steps= to allow it)");
                }
              }
              if (!(w.time() + 0.5 * w.dt() < t)) return false;
              if (w.time() + w.dt() == w.time()) {
                py::gil_scoped_acquire acquire;
                throw InputError("dt: " + num(w.dt()) + " s no longer advances time " + num(w.time()) + " s");
              }
              return true;
            });
          },
          py::arg("t"), py::kw_only(), py::arg("max_steps") = kMaxStepsPerCall,
          "Advances whole steps until time >= t [s]. ValueError for a non-finite t or one that needs more than "
          "max_steps steps (default 1e9); Ctrl-C raises KeyboardInterrupt between steps.")
      .def_property_readonly("time", [](Simulation& s) { return s.world().time(); })
      .def_property_readonly("dt", [](Simulation& s) { return s.world().dt(); })
      .def_property_readonly(
          "dt_rule", [](Simulation& s) { return s.world().dtRule(); },
          "Where dt came from: \"given\", \"one frame (1/60 s)\", or the rule (dt_period x dt_fraction) and its "
          "numbers.")
      .def_property_readonly(
          "integrator", [](Simulation& s) { return std::string(integratorKindName(s.world().settings().integrator)); },
          "The integrator that runs (what \"auto\" resolved to).")
      .def_property_readonly(
          "integrator_choice", [](Simulation& s) { return s.world().integratorChoice(); },
          "Why \"auto\" picked the integrator: both integrators' estimated wall seconds per simulated second "
          "(empty when the integrator was named).")
      .def_property_readonly("num_vertices", [](Simulation& s) { return s.world().model().numVertices(); })
      .def_property_readonly("num_elements", [](Simulation& s) { return s.world().model().numElements(); })
      .def_property(
          "positions",
          [](py::object self) { return stateView(self, self.cast<Simulation&>().world().state().positions); },
          [](Simulation& s, const py::array_t<double, py::array::forcecast>& a) {
            assignState(s, s.world().state().positions, a, "positions");
          },
          "(N, 3) float64 view of the vertex positions [m] (no copy, writable; not locked: see the thread-safety "
          "contract). Assigning `sim.positions = array` copies under the lock and refuses NaN / inf (ValueError); "
          "a NaN written into the view is refused by the next step.")
      .def_property(
          "velocities",
          [](py::object self) { return stateView(self, self.cast<Simulation&>().world().state().velocities); },
          [](Simulation& s, const py::array_t<double, py::array::forcecast>& a) {
            assignState(s, s.world().state().velocities, a, "velocities");
          },
          "(N, 3) float64 view of the vertex velocities [m/s] (as positions).")
      .def_property_readonly(
          "rest_positions", [](Simulation& s) { return vec3Array(std::vector<Vec3>(s.world().model().restPositions)); })
      .def_property_readonly("masses",
                             [](Simulation& s) { return realArray(std::vector<Real>(s.world().model().mass)); })
      .def_property_readonly(
          "stress",
          [](Simulation& s) {
            WorldLock lock(s);
            return realArray(s.world().vertexStress());
          },
          "Per-vertex von Mises stress [Pa] (mean of its elements').")
      .def_property_readonly(
          "element_stress",
          [](Simulation& s) {
            WorldLock lock(s);
            return realArray(s.world().elementStress());
          },
          "Per-element von Mises stress [Pa]: the element's small strain about its best-fit rotation in its "
          "region's material (its Young's modulus and Poisson's ratio).")
      .def_property_readonly(
          "strain",
          [](Simulation& s) {
            WorldLock lock(s);
            return realArray(s.world().vertexStrain());
          },
          "Per-vertex strain measure [-] (mean of its elements' element_strain).")
      .def_property_readonly(
          "element_strain",
          [](Simulation& s) {
            WorldLock lock(s);
            return realArray(s.world().elementStrain());
          },
          "Per-element strain measure [-]: RMS of |M R0_i - r_i| over its vertices divided by the element's size "
          "(the paper's fig. 1 measure).")
      .def_property_readonly("state_hash",
                             [](Simulation& s) {
                               WorldLock lock(s);
                               return s.world().stateHash();
                             })
      .def_property_readonly(
          "voxels", [](Simulation& s) { return volumeArray(std::make_shared<const VoxelVolume>(s.built.bodies[0].volume)); })
      .def("metrics",
           [](Simulation& s) {
             WorldLock lock(s);
             return metricsDict(s.world().metrics(), finiteState(s.world().state()));
           })
      .def(
          "body_metrics",
          [](Simulation& s) {
            WorldLock lock(s);
            const bool finite = finiteState(s.world().state());
            py::list out;
            for (const Metrics& x : s.world().bodyMetrics()) out.append(metricsDict(x, finite));
            return out;
          },
          "metrics() per body (a list, body order); metrics() is their sum.")
      .def_property_readonly("num_bodies", [](Simulation& s) { return s.built.numBodies(); })
      .def_property_readonly(
          "body_names",
          [](Simulation& s) {
            std::vector<std::string> names;
            for (size_t i = 0; i < s.built.numBodies(); ++i) names.push_back(s.built.bodies[i].name);
            return names;
          },
          "Each body's name (scene key bodies[i].name, default 'body<i>').")
      .def_property_readonly(
          "body_vertex_ranges",
          [](Simulation& s) {
            std::vector<std::pair<size_t, size_t>> r;
            for (const BodyRange& b : s.world().model().bodies) r.emplace_back(b.vertexBegin, b.vertexEnd);
            return r;
          },
          "Per body, (begin, end): its rows of positions, velocities, masses, ...")
      .def_property_readonly(
          "body_element_ranges",
          [](Simulation& s) {
            std::vector<std::pair<size_t, size_t>> r;
            for (const BodyRange& b : s.world().model().bodies) r.emplace_back(b.elementBegin, b.elementEnd);
            return r;
          },
          "Per body, (begin, end): its entries of element_stress.")
      .def(
          "body_positions",
          [](py::object self, size_t body) {
            Simulation& s = self.cast<Simulation&>();
            const BodyRange& r = bodyRange(s, body);
            return stateView(self, s.world().state().positions, r.vertexBegin, r.vertexEnd);
          },
          py::arg("body"), "(n, 3) view of one body's rows of positions (no copy, writable; as positions).")
      .def(
          "body_velocities",
          [](py::object self, size_t body) {
            Simulation& s = self.cast<Simulation&>();
            const BodyRange& r = bodyRange(s, body);
            return stateView(self, s.world().state().velocities, r.vertexBegin, r.vertexEnd);
          },
          py::arg("body"), "(n, 3) view of one body's rows of velocities (as velocities).")
      .def(
          "surface",
          [](Simulation& s, const std::string& kind, size_t body) {
            WorldLock lock(s);
            const BodyRange& range = bodyRange(s, body);
            const BuiltBody& b = s.built.bodies[body];
            TriangleMesh mesh;
            if (kind == "embedded") {
              // The body's mesh file carried by the elements; for a volume, its isosurface. In
              // the body's own vertex ids, moved to the world's (bodies.h).
              auto it = s.isoEmbedded.find(body);
              if (it == s.isoEmbedded.end()) {
                EmbeddedMesh em;
                if (b.embedded) {
                  em = *b.embedded;
                } else {
                  if (s.scene.dim != 3) throw InputError("surface: 'embedded' needs a 3D body or a mesh");
                  em = embedMesh(isosurface(b.volume, b.model->origin), b.layout, *b.model);
                }
                shiftVertexIds(em, range.vertexBegin, range.elementBegin);
                it = s.isoEmbedded.emplace(body, std::move(em)).first;
              }
              mesh = embeddedMesh(it->second, s.world().state().positions);
            } else {
              const SurfaceKind k = parseSurfaceKind(kind);
              auto it = s.surfaces.find({body, k});
              if (it == s.surfaces.end()) {
                DisplaySurface surface = buildDisplaySurface(b.layout, b.volume, k);
                shiftVertexIds(surface, range.vertexBegin);
                it = s.surfaces.emplace(std::make_pair(body, k), std::move(surface)).first;
              }
              mesh = surfaceMesh(it->second, s.world().state().positions);
            }
            auto tris = std::move(mesh.triangles);
            auto* owner = new std::vector<std::array<uint32_t, 3>>(std::move(tris));
            py::capsule base(owner, [](void* p) { delete static_cast<std::vector<std::array<uint32_t, 3>>*>(p); });
            py::array triangles =
                py::array_t<uint32_t>({py::ssize_t(owner->size()), py::ssize_t(3)},
                                      {py::ssize_t(sizeof(std::array<uint32_t, 3>)), py::ssize_t(sizeof(uint32_t))},
                                      owner->data()->data(), base);
            return py::make_tuple(vec3Array(std::move(mesh.vertices)), triangles, vec3Array(std::move(mesh.normals)));
          },
          py::arg("kind") = "smooth", py::arg("body") = 0,
          "A body's display surface now: (vertices (V, 3) [m], triangles (T, 3) uint32, normals (V, 3)); kind "
          "'smooth', 'voxel' or 'embedded' (the body's mesh file carried by the elements; for a volume, its "
          "isosurface).");
}
