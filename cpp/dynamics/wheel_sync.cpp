// The Jacobian wheel synchroniser of seed 004 §2.3 (wheel_sync.hpp): each wheel's Jacobian
// (eqs 1–2) and the wheel speeds from the body command, x = A⁺ y (eqs 9–10).
#include "ernest/dynamics/wheel_sync.hpp"

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <cmath>

#include "ernest/common/validation.hpp"

namespace ernest::dynamics {

WheelJacobian wheel_jacobian(const RoverParameters& p, double psi, double phi, int wheel) {
  require(wheel >= 0 && wheel < 4, "wheel_jacobian: wheel must be in 0..3");
  require_finite("wheel_jacobian", "psi", psi);
  require_finite("wheel_jacobian", "phi", phi);
  const bool front = wheel < 2;
  const Eigen::Vector3d g = p.gimbal_point();
  Eigen::Matrix3d rw = Eigen::Matrix3d::Identity();  // wheel frame in the chassis frame
  Eigen::Vector3d pos = p.wheel_centre(wheel);
  if (front) {
    rw = (Eigen::AngleAxisd(psi, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitX())).toRotationMatrix();
    pos = g + rw * (pos - g);
  }
  const Eigen::Matrix3d rt = rw.transpose();
  WheelJacobian j = WheelJacobian::Zero();
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(k);
    j.col(k) = rt * e;                // C_V: translation of the chassis
    j.col(3 + k) = rt * e.cross(pos);  // C_omega: rotation of the chassis about its origin
  }
  if (front) {
    const Eigen::Vector3d arm = pos - g;
    const Eigen::Vector3d roll_axis = rw.col(0);  // bogie x: roll about its own longitudinal axis
    j.col(6) = rt * Eigen::Vector3d::UnitZ().cross(arm);  // C_psi_dot (yaw about chassis z)
    j.col(7) = rt * roll_axis.cross(arm);                  // C_phi_dot
  }
  return j;
}

namespace {

using SyncCod = Eigen::CompleteOrthogonalDecomposition<Eigen::Matrix<double, 12, 11>>;

// cod.solve(rhs) without its heap temporary: Eigen 3.4's applyZAdjointOnTheLeftInPlace allocates
// a dynamic vector whenever A is rank-deficient (it is here), and the onboard loop calls this at
// 50 Hz, where it must not allocate. The same operations in the same order as Eigen's _solve_impl, so the
// result is bit-identical (checked against cod.solve in tests/cpp/test_dynamics.cpp).
Eigen::Matrix<double, 11, 1> cod_solve(const SyncCod& cod, const Eigen::Matrix<double, 12, 1>& rhs) {
  Eigen::Matrix<double, 11, 1> dst;
  const Eigen::Index rank = cod.rank(), cols = dst.rows();
  if (rank == 0) return dst.setZero();
  Eigen::Matrix<double, 12, 1> c = rhs;  // c = Q^* rhs
  c.applyOnTheLeft(cod.householderQ().setLength(rank).adjoint());
  dst.topRows(rank) = cod.matrixT().topLeftCorner(rank, rank).triangularView<Eigen::Upper>().solve(
      c.topRows(rank));  // T z = c(1:rank)
  if (rank < cols) {  // y = Z^* [z; 0]
    dst.bottomRows(cols - rank).setZero();
    double temp[11];
    for (Eigen::Index k = 0; k < rank; ++k) {
      if (k != rank - 1) dst.row(k).swap(dst.row(rank - 1));
      dst.middleRows(rank - 1, cols - rank + 1)
          .applyHouseholderOnTheLeft(cod.matrixQTZ().row(k).tail(cols - rank).adjoint(),
                                     cod.zCoeffs()(k), temp);
      if (k != rank - 1) dst.row(k).swap(dst.row(rank - 1));
    }
  }
  dst = cod.colsPermutation() * dst;  // x = P^-1 y
  return dst;
}

}  // namespace

Eigen::Matrix<double, 11, 1> pseudo_inverse_solve(const Eigen::Matrix<double, 12, 11>& a,
                                                  const Eigen::Matrix<double, 12, 1>& y) {
  return cod_solve(SyncCod(a), y);
}

WheelSyncResult synchronise_wheels(const RoverParameters& p, double psi, double phi, double vx,
                                   double wx, double wy, double psi_dot, double phi_dot) {
  // Physical ranges (1e200 used to pass and give infinite wheel speeds): the rates of Commands.
  const char* o = "synchronise_wheels";
  require_in_range(o, "psi", psi, -2.0 * M_PI, 2.0 * M_PI);
  require_in_range(o, "phi", phi, -2.0 * M_PI, 2.0 * M_PI);
  require_in_range(o, "vx", vx, -kMaxSyncSpeed, kMaxSyncSpeed);
  require_in_range(o, "wx", wx, -kMaxCommandRate, kMaxCommandRate);
  require_in_range(o, "wy", wy, -kMaxCommandRate, kMaxCommandRate);
  require_in_range(o, "psi_dot", psi_dot, -kMaxCommandRate, kMaxCommandRate);
  require_in_range(o, "phi_dot", phi_dot, -kMaxCommandRate, kMaxCommandRate);
  WheelSyncResult res;
  res.A.setZero();
  res.y.setZero();
  for (int i = 0; i < 4; ++i) {
    const WheelJacobian j = wheel_jacobian(p, psi, phi, i);
    const int r = 3 * i;
    // eq 6: unknown chassis rates (Vy, Vz, wz) and -I_3x2 on the wheel's (vx, vz) (eq 7).
    res.A.block<3, 1>(r, 0) = j.col(1);
    res.A.block<3, 1>(r, 1) = j.col(2);
    res.A.block<3, 1>(r, 2) = j.col(5);
    res.A(r + 0, 3 + 2 * i) = -1.0;
    res.A(r + 2, 4 + 2 * i) = -1.0;
    // eq 8: the known rates move to the right-hand side; v_y^i = 0 (no side slip) is omitted.
    res.y.segment<3>(r) =
        -(j.col(0) * vx + j.col(3) * wx + j.col(4) * wy + j.col(6) * psi_dot + j.col(7) * phi_dot);
  }
  // eq 9: x = A^+ y, minimum-norm least squares through a complete orthogonal decomposition.
  res.x = pseudo_inverse_solve(res.A, res.y);
  res.residual = (res.A * res.x - res.y).norm();
  for (int i = 0; i < 4; ++i) {
    const double vxi = res.x(3 + 2 * i), vzi = res.x(4 + 2 * i);
    const double sgn = (vxi > 0.0) - (vxi < 0.0);
    res.wheel_speeds[i] = sgn * std::sqrt(vxi * vxi + vzi * vzi) / p.wheel_radius;  // eq 10
  }
  return res;
}

}  // namespace ernest::dynamics
