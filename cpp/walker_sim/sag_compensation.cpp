#include "ernest/walker_sim/sag_compensation.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "ernest/common/validation.hpp"
#include "ernest/walker/stance_sag.hpp"

namespace ernest::walker_sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Heights of the hip mounts (chassis corners) for a body pose.
Eigen::VectorXd corner_heights(const walker::WalkerModel& model, const Eigen::Isometry3d& body) {
  Eigen::VectorXd z(model.legs());
  for (int k = 0; k < model.legs(); ++k) z[k] = (body * model.hip_mount(k).translation()).z();
  return z;
}

// §5.1.1 sag of the stance: the rigid feet and CG of configuration q at `body`, the wheels as
// springs (k_t, k_t, k_zz), the listed leg in the air (+inf lift, eq 9), the corners carried along.
statics::SagResult predict_sag(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
                               const Eigen::MatrixXd& q, const Eigen::Matrix3Xd& feet, int lifted,
                               const SagScenarioOptions& o) {
  const double kz = o.sim.contact_stiffness, kt = o.tangential_ratio * kz;
  const Eigen::Matrix3Xd stiffness = Eigen::Vector3d(kt, kt, kz).replicate(1, model.legs());
  statics::SagResult r = statics::solve_sag(walker::stance_sag_problem(model, body, feet, q, stiffness, lifted));
  require(r.status == statics::SagStatus::Converged,
          std::string("run_sag_scenario: the sag model did not converge: ") + statics::to_string(r.status));
  return r;
}

Eigen::Isometry3d pose_of(const statics::SagResult& r) { return walker::sagged_pose(r); }

}  // namespace

void SagScenarioOptions::validate() const {
  const char* o = "SagScenarioOptions";
  require_in_range(o, "leg", leg, 0, 11);
  for (int k = 0; k < 3; ++k) {
    require_in_range(o, "step", step[k], -5.0, 5.0);
    require_in_range(o, "rock_half_extents", rock_half_extents[k], 1e-3, 5.0);
  }
  require(step.norm() > 1e-3, "SagScenarioOptions.step must be longer than 1 mm");
  require_in_range(o, "planned_clearance", planned_clearance, 0.0, 1.0);
  require_in_range(o, "min_lift", min_lift, 0.0, 2.0);
  require_in_range(o, "lift_resolution", lift_resolution, 1e-5, 0.1);
  require_in_range(o, "tangential_ratio", tangential_ratio, 1e-6, 1e6);
  require_in_range(o, "settle_time", settle_time, 0.0, 60.0);
  sim.validate();
  execution.validate();
}

SwingPlan plan_swing_over_rocks(const walker::WalkerModel& model, const Eigen::Isometry3d& body, int leg,
                                const Eigen::Ref<const Eigen::VectorXd>& q_start, const Eigen::Vector3d& goal,
                                const std::vector<Rock>& rocks, const SagScenarioOptions& o) {
  o.validate();
  SwingPlan plan;
  plan.assumed_body = body;
  // Clearance grows with the lift (the wheel passes higher): coarse tests every 2 cm, then
  // bisection to the resolution; an unreachable lift ends the search.
  auto trial = [&](double h, SwingPlan& out) {
    try {
      out.path = swing_path(model, body, leg, q_start, goal, h);
    } catch (const std::invalid_argument&) {
      return false;
    }
    out.lift_height = h;
    out.planned_clearance = planned_clearance(model, body, leg, out.path, rocks);
    return out.planned_clearance >= o.planned_clearance;
  };
  double lo = o.min_lift, hi = -1.0;
  SwingPlan t;
  for (double h = o.min_lift; h <= 2.0; h += 0.02) {
    if (trial(h, t)) {
      hi = h;
      plan = t;
      break;
    }
    lo = h;
  }
  require(hi >= 0.0, "plan_swing_over_rocks: no lift up to 2 m clears the rocks by " +
                         std::to_string(o.planned_clearance) + " m");
  if (hi > o.min_lift)
    while (hi - lo > o.lift_resolution) {
      const double mid = 0.5 * (lo + hi);
      if (trial(mid, t)) {
        hi = mid;
        plan = t;
      } else {
        lo = mid;
      }
    }
  plan.assumed_body = body;
  return plan;
}

SagScenarioResult run_sag_scenario(const walker::WalkerModel& model, const SagScenarioOptions& o) {
  o.validate();
  model.check_leg(o.leg);
  SagScenarioResult out;
  const Eigen::Isometry3d body0 = model.standard_body_pose();
  const Eigen::MatrixXd q = model.standard_configuration();
  const Eigen::Matrix3Xd feet = model.contact_points(body0, q);
  out.start = feet.col(o.leg);
  const Eigen::Vector3d step = body0.linear() * o.step;
  out.goal = out.start + step;
  Rock rock;
  rock.half_extents = o.rock_half_extents;
  rock.centre = 0.5 * (out.start + out.goal);
  rock.centre.z() = o.rock_half_extents.z();
  rock.yaw = std::atan2(step.y(), step.x()) - 0.5 * kPi;  // the rock's y along the step
  out.rocks = {rock};

  // The rigid plan: the body where rigid kinematics puts it (wheels touching z = 0, no sag).
  out.rigid = plan_swing_over_rocks(model, body0, o.leg, q.col(o.leg), out.goal, out.rocks, o);
  // The compensated plan: the pose the sag model predicts with the leg at its first waypoint
  // (in the air, eq 9 with an infinite lift); planned twice, as the CG moves with the waypoint.
  out.predicted_six = predict_sag(model, body0, q, feet, -1, o);
  Eigen::MatrixXd ql = q;
  ql.col(o.leg) = out.rigid.path[1];
  for (int iteration = 0; iteration < 2; ++iteration) {
    out.predicted_lifted = predict_sag(model, body0, ql, feet, o.leg, o);
    out.compensated = plan_swing_over_rocks(model, pose_of(out.predicted_lifted), o.leg, q.col(o.leg),
                                            out.goal, out.rocks, o);
    ql.col(o.leg) = out.compensated.path[1];
  }
  out.predicted_lifted = predict_sag(model, body0, ql, feet, o.leg, o);

  out.rigid_corners = corner_heights(model, body0);
  out.predicted_six_corners = out.predicted_six.body_points.row(2).transpose();
  out.predicted_lifted_corners = out.predicted_lifted.body_points.row(2).transpose();
  for (int run = 0; run < 2; ++run) {
    WalkerSim sim(model, body0, q, out.rocks, o.sim);
    sim.hold(q, o.settle_time);
    if (run == 0) out.measured_six_corners = corner_heights(model, sim.body_pose());
    const SwingPlan& plan = run == 0 ? out.rigid : out.compensated;
    ExecutionTrace trace = execute_joint_path(sim, o.leg, q, plan.path, o.execution);
    if (run == 1) out.measured_lifted_corners = corner_heights(model, trace.waypoint_body.at(1));
    (run == 0 ? out.rigid_run : out.compensated_run) = std::move(trace);
  }
  out.six_error = (out.predicted_six_corners - out.measured_six_corners).cwiseAbs().maxCoeff();
  out.lifted_error = (out.predicted_lifted_corners - out.measured_lifted_corners).cwiseAbs().maxCoeff();
  return out;
}

}  // namespace ernest::walker_sim
