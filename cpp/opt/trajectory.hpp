// Joint-space transition trajectories: the C1 cubic spline through waypoints used by Bezier
// (eqs 9–13, two waypoints) and Linear/Spline (eqs 14–17, joined by cubic Bezier segments), and
// the Naive strategy's synchronised trapezoidal move.
#pragma once

#include <Eigen/Core>

namespace ernest::opt {

/// Weights of one spline sample as a linear combination of its sources: waypoints
/// W[first .. first+3] (entries with index outside [0, N) have weight 0) and the two end tangents.
/// Row d holds the weights of the d-th derivative with respect to normalised time s in [0, 1].
struct SplineStencil {
  int first = 0;                 ///< index of the first of the four waypoints
  double w[3][4] = {};           ///< weights of W[first + k] for value, d/ds, d2/ds2
  double start_tangent[3] = {};  ///< weights of the start tangent m_0 (in d/ds units)
  double end_tangent[3] = {};    ///< weights of the end tangent m_{N-1}
};

/// Stencil at local position u in [0, 1] of segment `segment` (0 .. N-2) of an N-waypoint spline.
/// Segment k is the cubic Bezier with control points
///   P0 = W_k, P1 = W_k + m_k ds/3, P2 = W_{k+1} - m_{k+1} ds/3, P3 = W_{k+1},
/// ds = 1/(N-1), interior tangents m_k = (W_{k+1} - W_{k-1}) / (2 ds) (Catmull–Rom), end tangents
/// given. With N = 2 this is exactly the Bezier of eqs 9–13 (see transition.hpp for the T/3).
void spline_stencil(int waypoints, int segment, double u, SplineStencil& out);
/// Same at normalised time s in [0, 1].
void spline_stencil_at(int waypoints, double s, SplineStencil& out);

/// Interior points of one cubic segment q(u), u in (0, 1), where its position or its velocity can
/// peak, from q'(0), q''(0) and q''(1) (derivatives with respect to u; q'' is linear in u):
///   roots of the quadratic q'(u) = q'(0) + q''(0) u + (q''(1) - q''(0)) u^2 / 2  (position extrema),
///   the zero of q''(u), the vertex of q' (velocity extremum).
/// Together with the segment ends these are every candidate for max |q| and max |q'| (exact).
struct CubicExtrema {
  int roots = 0;           ///< number of roots of q' strictly inside (0, 1)
  double root[2] = {};
  bool has_vertex = false; ///< q'' changes sign strictly inside (0, 1)
  double vertex = 0.0;
};
CubicExtrema cubic_extrema(double d1_0, double d2_0, double d2_1);

/// A C1 piecewise-cubic trajectory over t in [0, duration]: waypoints (joints x N, equally spaced in
/// time) and the end velocities (start_velocity, end_velocity) in joint units per second.
class SplineTrajectory {
 public:
  SplineTrajectory() = default;
  SplineTrajectory(Eigen::MatrixXd waypoints, Eigen::VectorXd start_velocity,
                   Eigen::VectorXd end_velocity, double duration);
  int joints() const { return static_cast<int>(waypoints_.rows()); }
  int size() const { return static_cast<int>(waypoints_.cols()); }
  double duration() const { return duration_; }
  const Eigen::MatrixXd& waypoints() const { return waypoints_; }
  /// Position, velocity, acceleration of joint j at t in [0, duration] (clamped).
  void evaluate(int j, double t, double& q, double& dq, double& ddq) const;
  /// Exact max over [0, duration] of |q_j| and |dq_j/dt| (segment ends and the interior extrema of
  /// every cubic segment, cubic_extrema), not a sampled estimate.
  void max_abs(int j, double& position, double& velocity) const;

 private:
  Eigen::MatrixXd waypoints_;
  Eigen::VectorXd start_velocity_, end_velocity_;
  double duration_ = 0.0;
};

/// Synchronised trapezoidal move from rest at `from` to rest at `to` (the Naive strategy): every
/// joint accelerates at its limit, cruises, decelerates, and all arrive together at the time of the
/// slowest joint.
class TrapezoidTrajectory {
 public:
  TrapezoidTrajectory() = default;
  TrapezoidTrajectory(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                      const Eigen::VectorXd& velocity_limit,
                      const Eigen::VectorXd& acceleration_limit);
  int joints() const { return static_cast<int>(from_.size()); }
  double duration() const { return duration_; }
  void evaluate(int j, double t, double& q, double& dq, double& ddq) const;
  /// Cruise velocity and acceleration magnitude used by joint j (<= its limits).
  double cruise_velocity(int j) const { return cruise_[j]; }
  double acceleration(int j) const { return accel_[j]; }

 private:
  Eigen::VectorXd from_, to_, cruise_, accel_, ramp_;
  double duration_ = 0.0;
};

}  // namespace ernest::opt
