#include "ernest/walker/sway_gait.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "ernest/common/validation.hpp"
#include "ernest/walker/leg_ik.hpp"

namespace ernest::walker {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Evaluates the phases of one gait, warm-starting each leg's IK from its last solution.
class PhaseEvaluator {
 public:
  PhaseEvaluator(const WalkerModel& model, const SwayGaitOptions& o)
      : model_(model), o_(o), ik_(model), seeds_(model.standard_configuration()) {
    const Eigen::Isometry3d body = model.standard_body_pose();
    standard_feet_ = model.contact_points(body, model.standard_configuration());
    direction_ = Eigen::Vector3d(std::cos(o.heading), std::sin(o.heading), 0.0);
  }

  GaitPhase evaluate(int phase, const Eigen::Vector3d& d) {
    const int legs = model_.legs(), steps = static_cast<int>(o_.sequence.size());
    GaitPhase out;
    out.lifted_leg = o_.sequence[phase];
    out.displacement = d;
    // Footfalls before this step: legs already stepped in this cycle are one stride ahead.
    Eigen::Matrix3Xd feet = standard_feet_;
    for (int s = 0; s < phase; ++s) feet.col(o_.sequence[s]) += o_.stride * direction_;
    // Reference body: over the centroid of the footfalls (one shift of stride/steps per step).
    out.body_position = Eigen::Vector3d(0, 0, model_.params().standard_height) +
                        (o_.stride * phase / steps) * direction_ + d;
    Eigen::Isometry3d body = Eigen::Isometry3d::Identity();
    body.translation() = out.body_position;
    const Eigen::Vector3d lift(0.0, 0.0, o_.lift_height);
    const std::vector<int> lifted{out.lifted_leg};
    out.reachable = true;
    for (int instant = 0; instant < 2; ++instant) {
      Eigen::Matrix3Xd f = feet;
      f.col(out.lifted_leg) += lift;
      if (instant == 1) f.col(out.lifted_leg) += o_.stride * direction_;
      Eigen::MatrixXd q(model_.joints_per_leg(), legs);
      for (int k = 0; k < legs; ++k) {
        const Eigen::Isometry3d target =
            upright_foot_pose(model_, body.inverse() * f.col(k), 2.0 * kPi * k / legs);
        if (!ik_.solve_from(k, target, seeds_.col(k), q.col(k))) {
          const IkResult r = ik_.solve(k, target, model_.standard_configuration().col(k));
          if (r.status != IkStatus::kSolved) {
            out.reachable = false;
            return out;
          }
          q.col(k) = r.solutions.front();
        }
        seeds_.col(k) = q.col(k);
      }
      StanceLoads loads = stance_loads(model_, body, q, lifted);
      (instant == 0 ? out.q_lift_off : out.q_touch_down) = q;
      (instant == 0 ? out.lift_off : out.touch_down) = std::move(loads);
    }
    out.peak_saturation = std::max(out.lift_off.peak_saturation, out.touch_down.peak_saturation);
    out.peak_force = std::max(out.lift_off.peak_force, out.touch_down.peak_force);
    out.support_margin = std::min(out.lift_off.support_margin, out.touch_down.support_margin);
    return out;
  }

 private:
  const WalkerModel& model_;
  const SwayGaitOptions& o_;
  LegIk ik_;
  Eigen::MatrixXd seeds_;
  Eigen::Matrix3Xd standard_feet_;
  Eigen::Vector3d direction_;
};

// Constraint values at displacement d: every saturation minus t at both instants, then the two
// support-margin constraints. Unreachable poses give a large violation.
void phase_constraints(PhaseEvaluator& ev, const SwayGaitOptions& o, int phase,
                       const Eigen::Vector3d& d, double t, double* c, int count) {
  const GaitPhase g = ev.evaluate(phase, d);
  if (!g.reachable) {
    std::fill(c, c + count, 10.0);
    return;
  }
  int i = 0;
  for (const StanceLoads* s : {&g.lift_off, &g.touch_down})
    for (Eigen::Index k = 0; k < s->saturation.size(); ++k) c[i++] = s->saturation.data()[k] - t;
  c[i++] = o.min_support_margin - g.lift_off.support_margin;
  c[i++] = o.min_support_margin - g.touch_down.support_margin;
}

}  // namespace

void SwayGaitOptions::validate(int legs) const {
  const char* o = "SwayGaitOptions";
  require_in_range(o, "legs", legs, 1, 64);  // sizes the seen-legs table below
  require_in_range(o, "stride", stride, 0.0, 5.0);
  require_finite(o, "heading", heading);
  require_in_range(o, "lift_height", lift_height, 0.0, 2.0);
  require(!sequence.empty(), "SwayGaitOptions.sequence is empty");
  std::vector<bool> seen(legs, false);
  for (int leg : sequence) {
    require(leg >= 0 && leg < legs && !seen[leg],
            "SwayGaitOptions.sequence must list distinct legs in [0, " + std::to_string(legs - 1) + "]");
    seen[leg] = true;
  }
  require_in_range(o, "max_shift_xy", max_shift_xy, 0.0, 2.0);
  require_in_range(o, "max_shift_up", max_shift_up, 0.0, 2.0);
  require_in_range(o, "max_shift_down", max_shift_down, 0.0, 2.0);
  require_in_range(o, "min_support_margin", min_support_margin, -10.0, 10.0);
  require_in_range(o, "fd_step", fd_step, 1e-9, 1e-2);
  solver.validate();
}

GaitPhase evaluate_gait_phase(const WalkerModel& model, const SwayGaitOptions& options, int phase,
                              const Eigen::Vector3d& displacement) {
  options.validate(model.legs());
  require(phase >= 0 && phase < static_cast<int>(options.sequence.size()),
          "phase = " + std::to_string(phase) + " is outside the gait's steps");
  require(displacement.allFinite(), "displacement is not finite");
  PhaseEvaluator ev(model, options);
  return ev.evaluate(phase, displacement);
}

SwayGaitResult optimise_sway_gait(const WalkerModel& model, const SwayGaitOptions& options) {
  options.validate(model.legs());
  const auto t0 = std::chrono::steady_clock::now();
  PhaseEvaluator ev(model, options);
  SwayGaitResult out;
  const int steps = static_cast<int>(options.sequence.size());
  const int count = 2 * model.joints_per_leg() * model.legs() + 2;
  out.reference_margin = out.sway_margin = kInf;
  for (int phase = 0; phase < steps; ++phase) {
    GaitPhase ref = ev.evaluate(phase, Eigen::Vector3d::Zero());
    require(ref.reachable, "optimise_sway_gait: the reference gait is unreachable at step " +
                               std::to_string(phase));
    // x = (d_x, d_y, d_z, t): minimise t, the phase's peak saturation.
    opt::OptimizationProblem pb;
    pb.dimension = 4;
    pb.objective = [](const double* x, double* grad) {
      if (grad) {
        grad[0] = grad[1] = grad[2] = 0.0;
        grad[3] = 1.0;
      }
      return x[3];
    };
    const double s = options.max_shift_xy;
    pb.lower = {-s, -s, -options.max_shift_down, 0.0};
    pb.upper = {s, s, options.max_shift_up, 10.0};
    std::vector<double> shifted(count);
    pb.inequality.push_back({count, [&](const double* x, double* c, double* jac) {
      const Eigen::Vector3d d(x[0], x[1], x[2]);
      phase_constraints(ev, options, phase, d, x[3], c, count);
      if (!jac) return;
      // Forward differences in d; d/dt = -1 on the saturation rows, 0 on the margin rows.
      for (int a = 0; a < 3; ++a) {
        Eigen::Vector3d dp = d;
        dp[a] += options.fd_step;
        phase_constraints(ev, options, phase, dp, x[3], shifted.data(), count);
        for (int r = 0; r < count; ++r) jac[r * 4 + a] = (shifted[r] - c[r]) / options.fd_step;
      }
      for (int r = 0; r < count; ++r) jac[r * 4 + 3] = r < count - 2 ? -1.0 : 0.0;
    }});
    const opt::SolverResult r = opt::minimize_slsqp(pb, {0.0, 0.0, 0.0, ref.peak_saturation}, options.solver);
    out.evaluations += r.evaluations;
    out.solver_status.push_back(r.status_name);
    GaitPhase best = ev.evaluate(phase, Eigen::Vector3d(r.x[0], r.x[1], r.x[2]));
    // Keep the reference when the solver did not find a feasible improvement.
    const bool ok = best.reachable && best.support_margin >= options.min_support_margin - 1e-6 &&
                    best.peak_saturation < ref.peak_saturation;
    if (!ok) best = ev.evaluate(phase, Eigen::Vector3d::Zero());
    out.reference_margin = std::min(out.reference_margin, 1.0 - ref.peak_saturation);
    out.sway_margin = std::min(out.sway_margin, 1.0 - best.peak_saturation);
    out.reference.push_back(std::move(ref));
    out.sway.push_back(std::move(best));
  }
  out.improvement = out.sway_margin / out.reference_margin - 1.0;
  out.peak_reduction = 1.0 - (1.0 - out.sway_margin) / (1.0 - out.reference_margin);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace ernest::walker
