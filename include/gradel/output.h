// Result files of a run (docs/scenes.md, "Output"): one VTK XML UnstructuredGrid per frame
// for ParaView, a .pvd collection that gives the frames their times, and metrics.csv; all
// written into an OutputDirectory, which makes the result appear at once or not at all.
#pragma once

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "gradel/model.h"
#include "gradel/world.h"

namespace gradel {

// ---- VTK frames -------------------------------------------------------------

/// How DataArrays are stored:
///   Raw (the default): VTK XML "appended" data, the raw little-endian bytes after the XML part
///     (exact, the smallest file and the fastest to write: no encoding pass); what VTK's own
///     writer, ParaView, meshio and pyvista read.
///   Base64: VTK XML "binary", base64 of the raw bytes inside each element (exact; the file is
///     well-formed XML throughout, 4/3 the size).
///   Ascii: shortest round-trip text (for reading by eye and in tests).
enum class VtkEncoding { Raw, Base64, Ascii };

/// One frame's .vtu file as bytes: the XML part, then (Raw) the appended data block. A caller
/// that writes frame after frame keeps one VtuBytes and lets encodeVtu refill it, so the buffers'
/// memory is reused rather than allocated (and faulted in) again every frame.
struct VtuBytes {
  std::string xml;       ///< Everything up to the appended data (without the closing tag).
  std::string appended;  ///< Raw: each array's UInt32 byte count and values, packed; else empty.
};

/// VTK cell types used by writeVtu.
inline constexpr uint8_t kVtkPolygon = 7;          ///< 2D elements.
inline constexpr uint8_t kVtkConvexPointSet = 41;  ///< 3D elements.

/// Writes one frame as a VTK XML UnstructuredGrid (.vtu).
///   points       state.positions [m] (z = 0 in 2D), Float64
///   cells        one per element. 3D: VTK_CONVEX_POINT_SET over the element's vertex list
///                (ParaView draws its convex hull; incomplete elements look convex). 2D:
///                VTK_POLYGON with the vertices in angular order about the element's rest
///                centroid, which traces the region's outline (every vertex of a 2D element
///                lies on its outline, layout.h). Connectivity and offsets Int32.
///   point data   "velocity" [m/s] (3 components), "stress" [Pa] (von Mises, World::vertexStress)
///                and "strain" [-] (World::vertexStrain), each when given; Float64
///   cell data    "level" (UInt8), "element_id" and "region" (several materials; Int32), and
///                "element_stress" [Pa] and "element_strain" [-] when given (Float64)
/// Throws std::invalid_argument on size mismatches, IoError (path and reason) on I/O errors.
void writeVtu(const std::filesystem::path& file, const RestModel& model, const State& state,
              const std::vector<Real>& vertexStress, const std::vector<Real>& elementStress = {},
              VtkEncoding encoding = VtkEncoding::Raw, const std::vector<Real>& vertexStrain = {},
              const std::vector<Real>& elementStrain = {});

/// The same for one body of a model of several (RestModel::bodies, bodies.h): its vertices and
/// elements only, vertex ids from 0 within the body, "element_id" the element's index within the
/// body. vertexStress / elementStress (and the strains) hold every vertex / element of the model (or are empty).
/// writeVtu above is this with one body covering the whole model.
void writeVtu(const std::filesystem::path& file, const RestModel& model, const State& state, const BodyRange& body,
              const std::vector<Real>& vertexStress, const std::vector<Real>& elementStress = {},
              VtkEncoding encoding = VtkEncoding::Raw, const std::vector<Real>& vertexStrain = {},
              const std::vector<Real>& elementStrain = {});

/// writeVtu in two halves: the file's bytes into `out` (refilled, its capacity kept), and the
/// bytes into a file (IoError naming the path on failure). FrameFileWriter writes them on its
/// own thread.
void encodeVtu(VtuBytes& out, const RestModel& model, const State& state, const BodyRange& body,
               const std::vector<Real>& vertexStress, const std::vector<Real>& elementStress = {},
               VtkEncoding encoding = VtkEncoding::Raw, const std::vector<Real>& vertexStrain = {},
               const std::vector<Real>& elementStrain = {});
void writeVtu(const std::filesystem::path& file, const VtuBytes& bytes);

/// "frame_00012.vtu": zero-padded so that file listings sort in time order. With a body name
/// (several bodies): "<body>_00012.vtu".
std::string frameFileName(size_t index, const std::string& body = "");

struct PvdFrame {
  Real time = 0;     ///< [s] simulated time of the frame.
  std::string file;  ///< Path relative to the .pvd file.
  int part = 0;      ///< Which dataset of the timestep (one per body): ParaView shows the parts as one multiblock.
  std::string name;  ///< The part's name (the body's), written when not empty.
};

/// Writes a ParaView collection (.pvd) that lists the frames with their times (and parts: one
/// entry per body and time).
void writePvd(const std::filesystem::path& file, const std::vector<PvdFrame>& frames);

/// Writes frame files on a thread of its own, so that a run steps on while the file system takes
/// in a frame (copying a box-realtime frame into the page cache was ~3 ms of a 10 ms frame write
/// in line, docs/speed.md "Frames"). Two buffers: the caller fills buffer() while the previous
/// frame is written; submit() waits for that write to end before handing over the next, so at
/// most one file is in flight and memory stays at two frames. Files are written whole and in
/// order; a failed write's IoError is rethrown by the next submit() or by finish().
class FrameFileWriter {
 public:
  FrameFileWriter();
  /// Waits for the file being written (a failure then is dropped: the caller is unwinding).
  ~FrameFileWriter();
  FrameFileWriter(const FrameFileWriter&) = delete;
  FrameFileWriter& operator=(const FrameFileWriter&) = delete;

  /// The buffer to fill for the next file (encodeVtu); never the one being written.
  VtuBytes& buffer();
  /// Writes buffer() to `file` in the background (after the previous file is done).
  void submit(const std::filesystem::path& file);
  /// Waits until every submitted file is written; rethrows the first failure.
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ---- metrics ----------------------------------------------------------------

/// metrics.csv: one row per frame from World::metrics(), every number written so that it
/// reads back to the same double (shortest round-trip form). With several bodies, a first
/// column `body`: per frame one row per body (World::bodyMetrics) and one row "all" (the world).
class MetricsCsv {
 public:
  /// The header line (no newline):
  /// time,kinetic_energy,elastic_energy,gravity_energy,px,py,pz,Lx,Ly,Lz,max_stress,
  /// max_penetration,max_contact_depth,min_element_det (max_stress [Pa]: von Mises), then the frame-averaged contact forces
  /// (Metrics::contactForces) the bodies exert: per manipulator k = 0, 1, ...
  /// m<k>_fx,m<k>_fy,m<k>_fz [N],m<k>_tx,m<k>_ty,m<k>_tz [N m] (about its centre), then the walls
  /// wall_fx,wall_fy,wall_fz,wall_tx,wall_ty,wall_tz (all walls together, torque about the
  /// origin), then the same six per wall, wall_<w>_fx .. wall_<w>_tz for w = xmin, xmax, ymin,
  /// ymax, zmin, zmax (contacts.h kWalls; zero for a wall no vertex touched), then max_strain [-]
  /// (Metrics::maxStrain, last so that the columns before it kept their places). With `carving`
  /// (a run with carving tools) then removed_voxels,removed_volume [m^3],removed_mass [kg]: what
  /// carving took since t = 0 (Metrics::removed; a body's own on its row, all bodies' on "all").
  /// With a body column, "body," first.
  static std::string header(size_t manipulators = 0, bool bodyColumn = false, bool carving = false);
  /// One data line (no newline); std::invalid_argument if m has forces for another number of
  /// manipulators. Without `forces` the force fields are left empty (a body's row: the forces are
  /// the world's, on the "all" row).
  static std::string row(const Metrics& m, size_t manipulators = 0, bool forces = true, bool carving = false);
  /// One data line with the body column first.
  static std::string row(const std::string& body, const Metrics& m, size_t manipulators = 0, bool forces = true,
                         bool carving = false);

  /// Creates the file and writes the header (with the body column and the carving columns when
  /// asked). Throws IoError on I/O errors.
  explicit MetricsCsv(const std::filesystem::path& file, size_t manipulators = 0, bool bodyColumn = false,
                      bool carving = false);
  ~MetricsCsv();
  MetricsCsv(const MetricsCsv&) = delete;
  MetricsCsv& operator=(const MetricsCsv&) = delete;

  void append(const Metrics& m);  ///< Without a body column.
  /// With a body column; `forces` false leaves the force fields empty (per-body rows).
  void append(const std::string& body, const Metrics& m, bool forces = true);
  /// Flushes and closes; throws IoError if any write failed (disk full, ...).
  void close();

 private:
  std::filesystem::path path_;
  size_t manipulators_ = 0;
  std::FILE* file_ = nullptr;
  int err_ = 0;  ///< errno of the first failed append.
  bool bodyColumn_ = false;
  bool carving_ = false;
  void writeLine(std::string line);
};

// ---- the output directory -----------------------------------------------------

/// Removes the temporary directories `<target>.tmp-<pid>-XXXXXX` beside `target` whose owning
/// process is gone (a run killed by SIGKILL or a power cut): no process has that pid here and
/// nobody holds the flock on its `.lock` file (a run in another pid namespace, e.g. a container
/// sharing the folder, does). Names of any other form are left alone. Returns how many were
/// removed. Never throws.
size_t removeStaleTemporaries(const std::filesystem::path& target);

/// Writes a result directory so that a failed or interrupted run never leaves a half-written
/// result and never destroys the previous one:
///   * everything is written into a sibling `<target>.tmp-<pid>-XXXXXX` (path()), after the
///     leftovers of dead runs are removed (removeStaleTemporaries);
///   * commit() moves an existing `<target>` aside, renames the temporary directory to
///     `<target>`, then deletes the old one (rolled back if the rename fails);
///   * destruction without commit() deletes the temporary directory and any parent
///     directories the constructor had to create; `<target>` is untouched.
class OutputDirectory {
 public:
  /// Creates the temporary directory. If `<target>` exists it must be a directory, and if it
  /// is not empty it must contain a file named `marker` (a previous result, e.g. "run.pvd"), so
  /// that a mistyped --out can never replace an unrelated directory. Violations, and a file where
  /// a parent directory should be, are InputError; failing to create the directories (read-only
  /// file system, no permission, disk full) is IoError. `marker` must not be empty.
  OutputDirectory(std::filesystem::path target, const std::string& marker);
  ~OutputDirectory();
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;

  /// The temporary directory to write into (until commit()).
  const std::filesystem::path& path() const { return temp_; }
  const std::filesystem::path& target() const { return target_; }
  std::filesystem::path file(const std::string& name) const { return temp_ / name; }

  /// Publishes the result as `<target>`. Throws IoError on failure, in which case the previous
  /// `<target>` is restored.
  void commit();
  /// Deletes the temporary directory now (also done by the destructor). Never throws.
  void abort() noexcept;
  bool committed() const { return committed_; }

 private:
  std::filesystem::path target_;
  std::filesystem::path temp_;
  std::vector<std::filesystem::path> createdParents_;  ///< Deepest first.
  bool committed_ = false;
  bool finished_ = false;
  int lockFd_ = -1;  ///< Holds the flock on path()/.lock until commit or abort.
  void unlock() noexcept;
};

}  // namespace gradel
