// Basic numeric types shared by every gradel module.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

namespace gradel {

using Real = double;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

/// Integer lattice point, in units of the finest voxel (a vertex of voxel (i,j,k) lies at
/// (i..i+1, j..j+1, k..k+1)). In 2D z is always 0.
using Int3 = Eigen::Matrix<int32_t, 3, 1>;

/// Every error a user can cause (bad file, bad parameter, empty volume) is thrown as this type;
/// the message names the file and field. The CLI turns it into exit code 2.
/// The file and the field are also kept as data (file(), field(), detail()), so that a caller
/// that re-reports an error at another place (a key path under its own, a scene file in front)
/// builds the new one from them instead of taking the message apart.
class InputError : public std::runtime_error {
 public:
  /// An error with no field known: detail() is the whole message.
  explicit InputError(const std::string& message) : std::runtime_error(message), detail_(message) {}
  /// An error at key path `field` ("material.poisson_ratio", "bodies[1].model") of `file` (a path,
  /// a scene's name, an API call; empty: unknown). The message is "file: field: detail", an empty
  /// part left out with its ": ".
  InputError(std::string file, std::string field, std::string detail)
      : std::runtime_error(join(file, field, detail)), file_(std::move(file)), field_(std::move(field)),
        detail_(std::move(detail)) {}

  const std::string& file() const { return file_; }
  const std::string& field() const { return field_; }
  /// The message without the file and the field.
  const std::string& detail() const { return detail_; }

  /// The same error as seen from `file`, its field under `prefix` ("simulation.", "material."):
  /// the message is `file`: `prefix` + this message when this error names no file.
  InputError at(const std::string& file, const std::string& prefix = "") const {
    if (!file_.empty() || field_.empty()) return InputError(file, "", prefix + what());
    return InputError(file, prefix + field_, detail_);
  }

 private:
  static std::string join(const std::string& file, const std::string& field, const std::string& detail) {
    std::string m;
    if (!file.empty()) m += file + ": ";
    if (!field.empty()) m += field + ": ";
    return m + detail;
  }

  std::string file_, field_, detail_;
};

/// Writing results failed in the operating system (disk full, read-only file system, no
/// permission): the message names the path and the system's reason. The CLI turns it into
/// exit code 5.
class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace gradel
