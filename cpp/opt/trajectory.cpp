// Joint-space transition trajectories (trajectory.hpp): the synchronised trapezoid of Naive and
// the C1 cubic spline through waypoints of Bezier, Linear and Spline, with exact extrema.
#include "ernest/opt/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "ernest/common/validation.hpp"

namespace ernest::opt {

void spline_stencil(int n, int k, double u, SplineStencil& st) {
  const double ds = 1.0 / (n - 1);
  const double v = 1.0 - u;
  // Bernstein weights of P0..P3 for value, d/du, d2/du2; divided by ds^d for d/ds.
  const double b[3][4] = {
      {v * v * v, 3.0 * v * v * u, 3.0 * v * u * u, u * u * u},
      {-3.0 * v * v, 3.0 * v * v - 6.0 * u * v, 6.0 * u * v - 3.0 * u * u, 3.0 * u * u},
      {6.0 * v, 6.0 * u - 12.0 * v, 6.0 * v - 12.0 * u, 6.0 * u}};
  st.first = k - 1;
  for (int d = 0; d < 3; ++d) {
    const double scale = d == 0 ? 1.0 : (d == 1 ? 1.0 / ds : 1.0 / (ds * ds));
    for (int i = 0; i < 4; ++i) st.w[d][i] = 0.0;
    st.start_tangent[d] = st.end_tangent[d] = 0.0;
    const double c0 = b[d][0] * scale, c1 = b[d][1] * scale, c2 = b[d][2] * scale,
                 c3 = b[d][3] * scale;
    // Local indices: 0 -> W_{k-1}, 1 -> W_k, 2 -> W_{k+1}, 3 -> W_{k+2}.
    st.w[d][1] += c0;  // P0 = W_k
    if (k == 0) {      // P1 = W_0 + m_0 ds / 3
      st.w[d][1] += c1;
      st.start_tangent[d] += c1 * ds / 3.0;
    } else {  // P1 = W_k + (W_{k+1} - W_{k-1}) / 6
      st.w[d][1] += c1;
      st.w[d][2] += c1 / 6.0;
      st.w[d][0] -= c1 / 6.0;
    }
    if (k + 1 == n - 1) {  // P2 = W_{N-1} - m_{N-1} ds / 3
      st.w[d][2] += c2;
      st.end_tangent[d] -= c2 * ds / 3.0;
    } else {  // P2 = W_{k+1} - (W_{k+2} - W_k) / 6
      st.w[d][2] += c2;
      st.w[d][3] -= c2 / 6.0;
      st.w[d][1] += c2 / 6.0;
    }
    st.w[d][2] += c3;  // P3 = W_{k+1}
  }
}

void spline_stencil_at(int n, double s, SplineStencil& st) {
  s = std::clamp(s, 0.0, 1.0);
  const double x = s * (n - 1);
  const int k = std::min(static_cast<int>(std::floor(x)), n - 2);
  spline_stencil(n, k, x - k, st);
}

CubicExtrema cubic_extrema(double d1_0, double d2_0, double d2_1) {
  CubicExtrema e;
  const double a = 0.5 * (d2_1 - d2_0), b = d2_0, c = d1_0;  // q'(u) = a u^2 + b u + c
  auto keep_root = [&e](double u) {
    if (std::isfinite(u) && u > 0.0 && u < 1.0) e.root[e.roots++] = u;
  };
  if (a == 0.0) {
    if (b != 0.0) keep_root(-c / b);
  } else {
    const double disc = b * b - 4.0 * a * c;
    if (disc >= 0.0) {
      // Stable pair: qq = -(b + sign(b) sqrt(disc)) / 2, roots qq / a and c / qq.
      const double qq = -0.5 * (b + std::copysign(std::sqrt(disc), b));
      keep_root(qq / a);
      if (qq != 0.0) keep_root(c / qq);
    }
  }
  if (e.roots == 2 && e.root[0] > e.root[1]) std::swap(e.root[0], e.root[1]);
  if (d2_0 != d2_1) {
    const double u = d2_0 / (d2_0 - d2_1);
    if (u > 0.0 && u < 1.0) {
      e.has_vertex = true;
      e.vertex = u;
    }
  }
  return e;
}

SplineTrajectory::SplineTrajectory(Eigen::MatrixXd waypoints, Eigen::VectorXd start_velocity,
                                   Eigen::VectorXd end_velocity, double duration)
    : waypoints_(std::move(waypoints)),
      start_velocity_(std::move(start_velocity)),
      end_velocity_(std::move(end_velocity)),
      duration_(duration) {
  require(waypoints_.cols() >= 2, "SplineTrajectory: at least two waypoints are required");
  require(start_velocity_.size() == waypoints_.rows() && end_velocity_.size() == waypoints_.rows(),
          "SplineTrajectory: end velocities must have one entry per joint");
  require_positive("SplineTrajectory", "duration", duration_);
  require(waypoints_.allFinite() && start_velocity_.allFinite() && end_velocity_.allFinite(),
          "SplineTrajectory: waypoints and velocities must be finite");
}

void SplineTrajectory::evaluate(int j, double t, double& q, double& dq, double& ddq) const {
  const int n = size();
  SplineStencil st;
  spline_stencil_at(n, t / duration_, st);
  // Tangents in d/ds units are the time velocities times the duration.
  const double m0 = start_velocity_[j] * duration_, m1 = end_velocity_[j] * duration_;
  double out[3];
  for (int d = 0; d < 3; ++d) {
    double acc = st.start_tangent[d] * m0 + st.end_tangent[d] * m1;
    for (int i = 0; i < 4; ++i) {
      const int idx = st.first + i;
      if (idx >= 0 && idx < n && st.w[d][i] != 0.0) acc += st.w[d][i] * waypoints_(j, idx);
    }
    out[d] = acc;
  }
  q = out[0];
  dq = out[1] / duration_;
  ddq = out[2] / (duration_ * duration_);
}

void SplineTrajectory::max_abs(int j, double& position, double& velocity) const {
  const int n = size();
  const double ds = 1.0 / (n - 1);
  const double m0 = start_velocity_[j] * duration_, m1 = end_velocity_[j] * duration_;
  // d-th derivative with respect to s of segment k at local u.
  auto at = [&](int k, double u, int d) {
    SplineStencil st;
    spline_stencil(n, k, u, st);
    double acc = st.start_tangent[d] * m0 + st.end_tangent[d] * m1;
    for (int i = 0; i < 4; ++i) {
      const int idx = st.first + i;
      if (idx >= 0 && idx < n) acc += st.w[d][i] * waypoints_(j, idx);
    }
    return acc;
  };
  position = velocity = 0.0;
  for (int k = 0; k < n - 1; ++k) {
    for (double u : {0.0, 1.0}) {
      position = std::max(position, std::abs(at(k, u, 0)));
      velocity = std::max(velocity, std::abs(at(k, u, 1)));
    }
    // Derivatives with respect to u are ds^d times those with respect to s.
    const CubicExtrema e =
        cubic_extrema(ds * at(k, 0.0, 1), ds * ds * at(k, 0.0, 2), ds * ds * at(k, 1.0, 2));
    for (int r = 0; r < e.roots; ++r) position = std::max(position, std::abs(at(k, e.root[r], 0)));
    if (e.has_vertex) velocity = std::max(velocity, std::abs(at(k, e.vertex, 1)));
  }
  velocity /= duration_;
}

TrapezoidTrajectory::TrapezoidTrajectory(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                         const Eigen::VectorXd& velocity_limit,
                                         const Eigen::VectorXd& acceleration_limit)
    : from_(from), to_(to) {
  const int n = static_cast<int>(from.size());
  require(to.size() == n && velocity_limit.size() == n && acceleration_limit.size() == n,
          "TrapezoidTrajectory: all vectors need one entry per joint");
  cruise_ = Eigen::VectorXd::Zero(n);
  accel_ = Eigen::VectorXd::Zero(n);
  ramp_ = Eigen::VectorXd::Zero(n);
  // Minimum time per joint: triangular when the distance is too short to reach v_max.
  double duration = 0.0;
  for (int j = 0; j < n; ++j) {
    require_positive("TrapezoidTrajectory", "velocity_limit", velocity_limit[j]);
    require_positive("TrapezoidTrajectory", "acceleration_limit", acceleration_limit[j]);
    const double d = std::abs(to[j] - from[j]), v = velocity_limit[j], a = acceleration_limit[j];
    const double tj = d <= v * v / a ? 2.0 * std::sqrt(d / a) : d / v + v / a;
    duration = std::max(duration, tj);
  }
  duration_ = duration;
  for (int j = 0; j < n; ++j) {
    const double d = std::abs(to[j] - from[j]), a = acceleration_limit[j];
    if (d == 0.0 || duration == 0.0) continue;
    // Same duration for every joint: d = vc (T - vc / a)  =>  vc = (aT - sqrt(a^2 T^2 - 4 a d)) / 2.
    const double disc = std::max(0.0, a * a * duration * duration - 4.0 * a * d);
    const double vc = 0.5 * (a * duration - std::sqrt(disc));
    cruise_[j] = vc;
    accel_[j] = a;
    ramp_[j] = vc / a;
  }
}

void TrapezoidTrajectory::evaluate(int j, double t, double& q, double& dq, double& ddq) const {
  const double sign = to_[j] >= from_[j] ? 1.0 : -1.0;
  const double a = accel_[j], vc = cruise_[j], tr = ramp_[j], T = duration_;
  t = std::clamp(t, 0.0, T);
  double s = 0.0, v = 0.0, acc = 0.0;
  if (vc == 0.0) {
    s = v = acc = 0.0;
  } else if (t < tr) {
    s = 0.5 * a * t * t;
    v = a * t;
    acc = a;
  } else if (t <= T - tr) {
    s = 0.5 * a * tr * tr + vc * (t - tr);
    v = vc;
    acc = 0.0;
  } else {
    const double r = T - t;
    s = std::abs(to_[j] - from_[j]) - 0.5 * a * r * r;
    v = a * r;
    acc = -a;
  }
  q = from_[j] + sign * s;
  dq = sign * v;
  ddq = sign * acc;
}

}  // namespace ernest::opt
