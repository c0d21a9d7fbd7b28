// Zero-interaction contact-force distribution (seed 003 §5.1.1): the minimum-norm solution of the
// six equilibrium equations in the 3N contact-force components, f = A^+ w, which the paper notes
// is the zero-interaction solution (for any two contacts the projections of their forces on the
// line joining them are equal: the legs do not "fight each other"). Robot-agnostic: contact
// positions, CG, mass and gravity in one world frame.
#pragma once

#include <Eigen/Core>

namespace ernest::statics {

/// Quality of one distribution.
struct DistributionInfo {
  /// Rank of the 6 x 3N equilibrium matrix A: 6 for three or more non-collinear contacts, 5 for
  /// collinear ones (no moment about their line), 3 for one contact, 0 for none.
  int rank = 0;
  /// |A f - w| / (m |g|) with moments over (m |g| L), L the contacts' spread: ~1e-16 when
  /// equilibrium is reachable, > 0 when it is not (A^+ w is then the least-squares answer).
  double residual = 0.0;
};

/// Writes into `forces` (3 x N, the reaction on the robot at each contact [N]) the solution
/// f = A^+ w of
///   sum_i f_i + m g = 0,   sum_i (p_i - o) x f_i + (cg - o) x m g = 0.
/// Since A^+ w lies in the range of A^T, f_i = a + b x p_i for two vectors a, b, from which the
/// zero-interaction property follows; taking moments about the contacts' centroid o makes A A^T
/// block-diagonal (N I and sum |p|^2 I - p p^T), so the 6 x 6 solve is two 3 x 3 ones (the second
/// through an eigen-decomposition pseudo-inverse, which covers collinear contacts). No allocation.
/// Throws std::invalid_argument naming the field for non-finite input or mass <= 0.
DistributionInfo zero_interaction_forces(const Eigen::Ref<const Eigen::Matrix3Xd>& contacts,
                                         const Eigen::Vector3d& cg, double mass,
                                         const Eigen::Vector3d& gravity,
                                         Eigen::Ref<Eigen::Matrix3Xd> forces);

/// Same, returning the forces (allocates the 3 x N result).
Eigen::Matrix3Xd zero_interaction_forces(const Eigen::Ref<const Eigen::Matrix3Xd>& contacts,
                                         const Eigen::Vector3d& cg, double mass,
                                         const Eigen::Vector3d& gravity,
                                         DistributionInfo* info = nullptr);

}  // namespace ernest::statics
