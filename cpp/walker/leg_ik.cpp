#include "ernest/walker/leg_ik.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <unsupported/Eigen/LevenbergMarquardt>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"

namespace ernest::walker {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPi;
// Halton bases for up to 12 joints.
constexpr int kPrimes[12] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37};

double halton(int index, int base) {
  double f = 1.0, r = 0.0;
  for (int i = index; i > 0; i /= base) {
    f /= base;
    r += f * (i % base);
  }
  return r;
}

// Rotation angle between two rotation matrices from the chord ||A − B||_F = 2√2 sin(θ/2),
// accurate near zero (unlike acos of the trace).
double rotation_angle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const double chord = (a - b).norm() / (2.0 * std::sqrt(2.0));
  return 2.0 * std::asin(std::min(1.0, chord));
}
}  // namespace

void IkOptions::validate() const {
  const char* o = "IkOptions";
  require_in_range(o, "seeds", seeds, 1, 10000);
  require_in_range(o, "max_evaluations", max_evaluations, 1, 1e6);
  require_positive(o, "position_tolerance", position_tolerance);
  require_positive(o, "orientation_tolerance", orientation_tolerance);
  require_positive(o, "orientation_weight", orientation_weight);
  require_positive(o, "duplicate_tolerance", duplicate_tolerance);
  require_in_range(o, "max_solutions", max_solutions, 1, 10000);
}

// Residual r(u) = [wheel centre − target; w · vec(R − R*)] (12 rows): zero exactly at the target
// pose (a 3-vector rotation error would also vanish at 180° flips). Jacobian: column i of
// d/dq is [axis_i × (centre − joint_i); w · axis_i × R_k for each column k], times dq/du.
struct LegIk::Impl : Eigen::DenseFunctor<double> {
  Impl(const WalkerModel& model, const IkOptions& options)
      : Eigen::DenseFunctor<double>(model.joints_per_leg(), 12),
        model(model),
        ws(model),
        lm(*this) {
    const int n = model.joints_per_leg();
    centre.resize(n);
    half.resize(n);
    bounded.resize(n);
    q.resize(n);
    u.resize(n);
    for (int i = 0; i < n; ++i) {
      const double lo = model.lower_limits()[i], hi = model.upper_limits()[i];
      bounded[i] = hi - lo < kTwoPi - 1e-9;
      centre[i] = 0.5 * (lo + hi);
      half[i] = 0.5 * (hi - lo);
    }
    weight = options.orientation_weight;
    // Zero-residual problem: stop as soon as |r| is 1000× below the acceptance tolerances (the
    // iterations converge quadratically there); MINPACK's relative tests are only the fallback.
    stop_norm = 1e-3 * std::min(options.position_tolerance,
                                options.orientation_weight * options.orientation_tolerance);
    lm.setMaxfev(options.max_evaluations);
    lm.setFtol(1e-12);
    lm.setXtol(1e-12);
    lm.setGtol(0.0);
  }

  void to_q(const Eigen::VectorXd& x, Eigen::VectorXd& out) const {
    for (Eigen::Index i = 0; i < x.size(); ++i)
      out[i] = bounded[i] ? centre[i] + half[i] * std::sin(x[i]) : x[i];
  }
  void to_u(const Eigen::Ref<const Eigen::VectorXd>& qin, Eigen::VectorXd& out) const {
    for (Eigen::Index i = 0; i < qin.size(); ++i) {
      const double lo = model.lower_limits()[i], hi = model.upper_limits()[i];
      const double qi = std::min(std::max(qin[i], lo), hi);
      // Strictly inside, so no joint starts where dq/du = 0.
      out[i] = bounded[i] ? std::asin(std::clamp((qi - centre[i]) / half[i], -0.99, 0.99)) : qi;
    }
  }

  int operator()(const InputType& x, ValueType& f) const {
    to_q(x, q);
    model.forward(leg, q, ws);
    f.head<3>() = ws.wheel_centre - target_p;
    for (int k = 0; k < 3; ++k)
      f.segment<3>(3 + 3 * k) = weight * (ws.foot_rotation.col(k) - target_r.col(k));
    ++evaluations;
    return 0;
  }
  int df(const InputType& x, JacobianType& J) const {
    to_q(x, q);
    model.forward(leg, q, ws);
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      const double s = bounded[i] ? half[i] * std::cos(x[i]) : 1.0;
      const Eigen::Vector3d a = ws.joint_axis.col(i);
      J.block<3, 1>(0, i) = s * a.cross(ws.wheel_centre - ws.joint_position.col(i));
      for (int k = 0; k < 3; ++k)
        J.block<3, 1>(3 + 3 * k, i) = (s * weight) * a.cross(ws.foot_rotation.col(k));
    }
    return 0;
  }

  const WalkerModel& model;
  mutable LegWorkspace ws;
  mutable Eigen::VectorXd q;
  mutable int evaluations = 0;
  Eigen::VectorXd centre, half, u;
  std::vector<bool> bounded;
  double weight = 0.5;
  double stop_norm = 1e-9;
  int leg = 0;
  Eigen::Vector3d target_p = Eigen::Vector3d::Zero();
  Eigen::Matrix3d target_r = Eigen::Matrix3d::Identity();
  Eigen::LevenbergMarquardt<Impl> lm;
  double position_error = 0.0, orientation_error = 0.0;
};

LegIk::LegIk(const WalkerModel& model, const IkOptions& options)
    : model_(model), options_(options) {
  options_.validate();
  impl_ = std::make_unique<Impl>(model_, options_);
}

LegIk::~LegIk() = default;

bool LegIk::solve_from(int leg, const Eigen::Isometry3d& target,
                       const Eigen::Ref<const Eigen::VectorXd>& seed, Eigen::Ref<Eigen::VectorXd> q) {
  model_.check_leg(leg);
  model_.check_q(seed, "seed");
  require(q.size() == model_.joints_per_leg(), "q has the wrong size");
  const Eigen::Matrix3d r = target.linear();
  require(target.translation().allFinite() && r.allFinite(), "target is not finite");
  require((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-6 && r.determinant() > 0.0,
          "target rotation is not a rotation matrix");
  Impl& m = *impl_;
  m.leg = leg;
  m.target_p = target.translation();
  m.target_r = r;
  m.evaluations = 0;
  m.to_u(seed, m.u);
  // minimize() with one more stopping test: the residual norm (see stop_norm).
  auto status = m.lm.minimizeInit(m.u);
  if (status != Eigen::LevenbergMarquardtSpace::ImproperInputParameters) {
    do {
      if (m.lm.fnorm() <= m.stop_norm) break;
      poll_interrupt();  // Ctrl-C between solver iterations (common/interrupt.hpp)
      status = m.lm.minimizeOneStep(m.u);
    } while (status == Eigen::LevenbergMarquardtSpace::Running);
  }
  m.to_q(m.u, m.q);
  // Unbounded joints (a full turn of range) are wrapped into [lower, lower + 2π).
  for (int i = 0; i < q.size(); ++i) {
    double qi = m.q[i];
    if (!m.bounded[i]) {
      const double lo = model_.lower_limits()[i];
      qi = lo + std::fmod(std::fmod(qi - lo, kTwoPi) + kTwoPi, kTwoPi);
    }
    q[i] = qi;
  }
  model_.forward(leg, q, m.ws);
  m.position_error = (m.ws.wheel_centre - m.target_p).norm();
  m.orientation_error = rotation_angle(m.ws.foot_rotation, m.target_r);
  return m.position_error <= options_.position_tolerance &&
         m.orientation_error <= options_.orientation_tolerance;
}

IkResult LegIk::solve(int leg, const Eigen::Isometry3d& target,
                      const Eigen::Ref<const Eigen::VectorXd>& seed) {
  const int n = model_.joints_per_leg();
  model_.check_q(seed, "seed");
  const Eigen::VectorXd& lo = model_.lower_limits();
  const Eigen::VectorXd& hi = model_.upper_limits();
  // Joint-space distance with full-turn joints compared modulo 2π.
  auto distance = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    double d = 0.0;
    for (int i = 0; i < n; ++i) {
      double di = std::abs(a[i] - b[i]);
      if (!impl_->bounded[i]) di = std::min(di, kTwoPi - std::fmod(di, kTwoPi));
      d = std::max(d, di);
    }
    return d;
  };
  IkResult result;
  double best = std::numeric_limits<double>::infinity();
  Eigen::VectorXd start(n), q(n);
  for (int s = 0; s < options_.seeds; ++s) {
    poll_interrupt();  // Ctrl-C between starts (common/interrupt.hpp)
    if (s == 0) {
      start = seed;
    } else {
      for (int i = 0; i < n; ++i) start[i] = lo[i] + (hi[i] - lo[i]) * halton(s, kPrimes[i % 12]);
    }
    const bool ok = solve_from(leg, target, start, q);
    result.evaluations += impl_->evaluations;
    const double score = impl_->position_error + options_.orientation_weight * impl_->orientation_error;
    if (score < best) {
      best = score;
      result.closest = q;
      result.position_error = impl_->position_error;
      result.orientation_error = impl_->orientation_error;
    }
    if (!ok) continue;
    const bool duplicate = std::any_of(result.solutions.begin(), result.solutions.end(),
                                       [&](const Eigen::VectorXd& other) {
                                         return distance(other, q) < options_.duplicate_tolerance;
                                       });
    if (!duplicate) result.solutions.push_back(q);
    if (static_cast<int>(result.solutions.size()) >= options_.max_solutions) break;
  }
  std::stable_sort(result.solutions.begin(), result.solutions.end(),
                   [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
                     return distance(a, seed) < distance(b, seed);
                   });
  if (!result.solutions.empty()) {
    result.status = IkStatus::kSolved;
    // Report the errors of the first (nearest) solution.
    model_.forward(leg, result.solutions.front(), impl_->ws);
    result.closest = result.solutions.front();
    result.position_error = (impl_->ws.wheel_centre - target.translation()).norm();
    result.orientation_error = rotation_angle(impl_->ws.foot_rotation, target.linear());
  }
  return result;
}

double LegIk::last_position_error() const { return impl_->position_error; }
double LegIk::last_orientation_error() const { return impl_->orientation_error; }
int LegIk::last_evaluations() const { return impl_->evaluations; }

}  // namespace ernest::walker
