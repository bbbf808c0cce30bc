// Basic numeric types shared by every gradel module.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <stdexcept>
#include <string>

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
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Writing results failed in the operating system (disk full, read-only file system, no
/// permission): the message names the path and the system's reason. The CLI turns it into
/// exit code 5.
class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace gradel
