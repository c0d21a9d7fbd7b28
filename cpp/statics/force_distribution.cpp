// Zero-interaction distribution by the pseudo-inverse (seed 003 §5.1.1); see the header.
#include "ernest/statics/force_distribution.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "ernest/common/validation.hpp"

namespace ernest::statics {

DistributionInfo zero_interaction_forces(const Eigen::Ref<const Eigen::Matrix3Xd>& contacts,
                                         const Eigen::Vector3d& cg, double mass,
                                         const Eigen::Vector3d& gravity,
                                         Eigen::Ref<Eigen::Matrix3Xd> forces) {
  require(contacts.allFinite(), "contacts contains a non-finite value");
  require(cg.allFinite(), "cg contains a non-finite value");
  require(gravity.allFinite(), "gravity contains a non-finite value");
  require_positive("zero_interaction_forces", "mass", mass);
  const int n = static_cast<int>(contacts.cols());
  require(forces.cols() == n, "forces must have one column per contact");
  DistributionInfo info;
  if (n == 0) {
    info.residual = gravity.norm() > 0.0 ? 1.0 : 0.0;
    return info;
  }
  const Eigen::Vector3d o = contacts.rowwise().mean();
  const Eigen::Vector3d weight = mass * gravity;
  const Eigen::Vector3d F = -weight;                // required sum of the contact forces
  const Eigen::Vector3d M = -(cg - o).cross(weight);  // required moment about o
  Eigen::Matrix3d J = Eigen::Matrix3d::Zero();       // sum |p|^2 I - p p^T
  double spread = 0.0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = contacts.col(i) - o;
    J += p.squaredNorm() * Eigen::Matrix3d::Identity() - p * p.transpose();
    spread = std::max(spread, p.norm());
  }
  // Pseudo-inverse of J: eigenvalues below 1e-12 of the largest are treated as zero (collinear
  // contacts have one zero eigenvalue along their line; a single contact has J = 0).
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(J);
  const Eigen::Vector3d ev = eig.eigenvalues();
  const double cutoff = 1e-12 * std::max(ev.cwiseAbs().maxCoeff(), 1e-300);
  Eigen::Vector3d inv = Eigen::Vector3d::Zero();
  int rank_j = 0;
  for (int k = 0; k < 3; ++k) {
    if (ev(k) > cutoff) {
      inv(k) = 1.0 / ev(k);
      ++rank_j;
    }
  }
  const Eigen::Vector3d b = eig.eigenvectors() * inv.asDiagonal() *
                            (eig.eigenvectors().transpose() * M);
  const Eigen::Vector3d a = F / n;
  Eigen::Vector3d sum_f = Eigen::Vector3d::Zero(), sum_m = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = contacts.col(i) - o;
    forces.col(i) = a + b.cross(p);
    sum_f += forces.col(i);
    sum_m += p.cross(forces.col(i));
  }
  info.rank = 3 + rank_j;
  const double w = weight.norm();
  if (w > 0.0) {
    const double L = std::max({spread, (cg - o).norm(), 1e-12});
    info.residual = std::hypot((sum_f - F).norm() / w, (sum_m - M).norm() / (w * L));
  }
  return info;
}

Eigen::Matrix3Xd zero_interaction_forces(const Eigen::Ref<const Eigen::Matrix3Xd>& contacts,
                                         const Eigen::Vector3d& cg, double mass,
                                         const Eigen::Vector3d& gravity, DistributionInfo* info) {
  Eigen::Matrix3Xd forces(3, contacts.cols());
  const DistributionInfo i = zero_interaction_forces(contacts, cg, mass, gravity, forces);
  if (info) *info = i;
  return forces;
}

}  // namespace ernest::statics
