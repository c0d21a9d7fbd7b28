// 4 x 4 homogeneous transforms from Python, shared by the binding files: checked (finite, last row
// 0 0 0 1, a proper rotation block), ValueError naming the argument otherwise.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <stdexcept>
#include <string>

namespace ernest::bindings {

inline Eigen::Isometry3d to_isometry(const Eigen::Matrix4d& t, const char* field) {
  if (!t.allFinite()) throw std::invalid_argument(std::string(field) + " is not finite");
  if ((t.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9)
    throw std::invalid_argument(std::string(field) + " must have last row (0, 0, 0, 1)");
  const Eigen::Matrix3d r = t.topLeftCorner<3, 3>();
  if ((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > 1e-6 || r.determinant() <= 0.0)
    throw std::invalid_argument(std::string(field) + " rotation block is not a rotation matrix");
  Eigen::Isometry3d iso = Eigen::Isometry3d::Identity();
  iso.linear() = r;
  iso.translation() = t.topRightCorner<3, 1>();
  return iso;
}

}  // namespace ernest::bindings
