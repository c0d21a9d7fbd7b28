#include "ernest/walker_sim/footfall_cycle.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "ernest/common/validation.hpp"
#include "ernest/walker/gait_planner.hpp"
#include "ernest/walker/leg_ik.hpp"

namespace ernest::walker_sim {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The terrain within `radius` of (x, y) varies by at most `tolerance` (sampled on its own grid).
bool flat_around(const dynamics::HeightMap& t, double x, double y, double radius, double tolerance) {
  const double h = t.spacing();
  const int n = static_cast<int>(std::ceil(radius / h));
  double lo = kInf, hi = -kInf;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j) {
      if (std::hypot(i * h, j * h) > radius) continue;
      const double z = t.height(x + i * h, y + j * h);
      lo = std::min(lo, z), hi = std::max(hi, z);
      if (hi - lo > tolerance) return false;
    }
  return true;
}

// Stable rock-free cells of the map, nearest the nominal foothold first, spaced apart (at most max_candidates).
std::vector<Eigen::Vector2d> foothold_candidates(const footfall::StabilityMap& m, const dynamics::HeightMap& t,
                                                 const Eigen::Vector2d& nominal, const FootfallCycleOptions& o) {
  std::vector<std::pair<double, Eigen::Vector2d>> stable;
  const bool by_torque = o.torque_preference > 0.0 && m.saturation.size() == m.status.size();
  for (Eigen::Index i = 0; i < m.status.rows(); ++i)
    for (Eigen::Index j = 0; j < m.status.cols(); ++j)
      if (m.status(i, j) == static_cast<std::uint8_t>(footfall::CellStatus::kStable)) {
        const Eigen::Vector2d p(m.origin_x + i * m.cell, m.origin_y + j * m.cell);
        // §7.1: prefer cells by torque margin when asked (overloaded cells are never candidates).
        if (by_torque && std::isfinite(m.saturation(i, j)))
          stable.emplace_back((p - nominal).norm() + o.torque_preference * m.saturation(i, j), p);
        else
          stable.emplace_back((p - nominal).squaredNorm(), p);
      }
  std::sort(stable.begin(), stable.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Eigen::Vector2d> out;
  for (const auto& [d, p] : stable) {
    if (static_cast<int>(out.size()) >= o.max_candidates) break;
    const bool spaced = std::all_of(out.begin(), out.end(), [&](const Eigen::Vector2d& c) {
      return (c - p).norm() >= o.candidate_spacing;
    });
    if (spaced && flat_around(t, p.x(), p.y(), o.foothold_radius, o.flat_tolerance)) out.push_back(p);
  }
  return out;
}

// Joint angles keeping every foot on its contact point with the body at `body` (a body shift).
Eigen::MatrixXd stance_for(const walker::WalkerModel& model, const dynamics::HeightMap& terrain,
                           const Eigen::Isometry3d& body, const Eigen::MatrixXd& q, const Eigen::Matrix3Xd& feet,
                           const footfall::StabilityMapOptions& mo) {
  Eigen::MatrixXd out = q;
  walker::LegIk ik(model);
  for (int k = 0; k < model.legs(); ++k) {
    const footfall::StabilityMapper mapper(model, terrain, body, out, k, mo);
    const walker::IkResult r = ik.solve(k, mapper.target(feet.col(k), 0.0), out.col(k));
    require(r.status == walker::IkStatus::kSolved,
            "run_footfall_cycle: after the body shift leg " + std::to_string(k) + " cannot reach its foot");
    out.col(k) = r.solutions.front();
  }
  return out;
}

}  // namespace

void FootfallCycleOptions::validate(int joints) const {
  const char* o = "FootfallCycleOptions";
  require_in_range(o, "stride", stride, 1e-3, 2.0);
  require_finite(o, "heading", heading);
  require_in_range(o, "foothold_radius", foothold_radius, 0.0, 2.0);
  require_in_range(o, "flat_tolerance", flat_tolerance, 0.0, 1.0);
  require_in_range(o, "max_candidates", max_candidates, 1, 10000);
  require_in_range(o, "candidate_spacing", candidate_spacing, 0.0, 2.0);
  require_in_range(o, "settle_time", settle_time, 0.0, 60.0);
  require_in_range(o, "torque_preference", torque_preference, 0.0, 100.0);
  if (steps) require_in_range(o, "steps", *steps, 1, 1000);
  step.validate(joints);
  sim.validate();
  execution.validate();
}

FootfallCycleResult run_footfall_cycle(const walker::WalkerModel& model, const dynamics::HeightMap& terrain,
                                       const std::vector<Rock>& rocks, const FootfallCycleOptions& o) {
  o.validate(model.joints_per_leg());
  FootfallCycleResult out;
  Eigen::Isometry3d body = model.standard_body_pose();
  Eigen::MatrixXd q = model.standard_configuration();
  Eigen::Matrix3Xd feet = model.contact_points(body, q);
  const Eigen::Matrix3Xd feet0 = feet;
  const Eigen::Vector3d dir(std::cos(o.heading), std::sin(o.heading), 0.0);
  WalkerSim sim(model, body, q, rocks, o.sim);
  if (o.execute) sim.hold(q, o.settle_time);
  ExecutionTrace unexecuted;  // the traces of a planned-only cycle: nothing measured
  unexecuted.min_rock_clearance = unexecuted.min_any_rock_clearance = unexecuted.min_ground_clearance =
      std::numeric_limits<double>::quiet_NaN();
  out.body_start = sim.body_pose().translation();
  out.min_rock_clearance = kInf;
  const double sim_start = sim.time();
  double sim_wall = 0.0, plan_wall = 0.0;
  auto keep_frames = [&](const ExecutionTrace& t) {
    const Eigen::Index n0 = out.frame_time.size(), n = t.frame_time.size();
    out.frame_time.conservativeResize(n0 + n);
    out.frame_time.tail(n) = t.frame_time.array() + (sim.time() - t.simulated_seconds - sim_start);
    out.frame_body.insert(out.frame_body.end(), t.frame_body.begin(), t.frame_body.end());
    out.frame_q.insert(out.frame_q.end(), t.frame_q.begin(), t.frame_q.end());
  };
  std::vector<int> order = walker::reverse_wave_sequence(model, o.heading);
  if (o.steps) {
    require(*o.steps <= model.legs(), "FootfallCycleOptions.steps = " + std::to_string(*o.steps) +
                                          " is outside the allowed range [1, " +
                                          std::to_string(model.legs()) + "]");
    order.resize(*o.steps);
  }
  for (int leg : order) {
    FootfallStepRecord r;
    r.leg = leg;
    r.body_before = body.translation();
    const auto t0 = Clock::now();
    footfall::StabilityMapper mapper(model, terrain, body, q, leg, o.step.map);
    r.map = mapper.map();
    r.map_seconds = since(t0);
    r.nominal_goal = (feet0.col(leg) + o.stride * dir).head<2>();
    for (const Eigen::Vector2d& g : foothold_candidates(r.map, terrain, r.nominal_goal, o)) {
      ++r.candidates_tried;
      r.plan = footfall::plan_step(model, terrain, body, q, leg, g.x(), g.y(), o.step);
      if (r.plan.status == footfall::PlanStatus::kSolved) break;
    }
    plan_wall += since(t0);
    if (r.plan.status != footfall::PlanStatus::kSolved) {
      out.reason = "leg " + std::to_string(leg) + ": " +
                   (r.candidates_tried ? "no plan to any of " + std::to_string(r.candidates_tried) +
                                             " footholds (last: " + r.plan.reason + ")"
                                       : std::string("no stable rock-free foothold on the map"));
      out.steps.push_back(std::move(r));
      break;
    }
    // Execute the swing: the planned joint path, the other legs holding the stance.
    std::vector<Eigen::VectorXd> path;
    for (Eigen::Index c = 0; c < r.plan.path.cols(); ++c) path.emplace_back(r.plan.path.col(c));
    r.planned_clearance = planned_clearance(model, r.plan.planning_body, leg, path, rocks, 20);
    const int per_segment = 20;
    r.planned_wheel.resize(3, per_segment * (r.plan.path.cols() - 1) + 1);
    for (Eigen::Index c = 0; c + 1 < r.plan.path.cols(); ++c)
      for (int s = 0; s < per_segment; ++s) {
        const double u = static_cast<double>(s) / per_segment;
        const Eigen::VectorXd qi = (1.0 - u) * r.plan.path.col(c) + u * r.plan.path.col(c + 1);
        r.planned_wheel.col(c * per_segment + s) = (r.plan.planning_body * model.foot_pose(leg, qi)).translation();
      }
    r.planned_wheel.rightCols<1>() = (r.plan.planning_body * model.foot_pose(leg, path.back())).translation();
    const auto t1 = Clock::now();
    const ExecutionTrace swing = !o.execute ? unexecuted : execute_joint_path(sim, leg, q, path, o.execution);
    keep_frames(swing);
    r.executed_wheel = swing.wheel_path;
    r.swing_rock_clearance = swing.min_rock_clearance;
    r.transfer_ground_clearance = swing.min_ground_clearance;
    r.min_rock_clearance = swing.min_any_rock_clearance;
    q.col(leg) = r.plan.q_goal;
    feet = model.contact_points(body, q);
    // Body shift with every foot down: stride / legs along the heading.
    Eigen::Isometry3d next = body;
    next.translation() += (o.stride / model.legs()) * dir;
    const Eigen::MatrixXd q_next = stance_for(model, terrain, next, q, feet, o.step.map);
    const ExecutionTrace shift = !o.execute ? unexecuted : execute_configuration_path(sim, std::nullopt, {q, q_next}, o.execution);
    keep_frames(shift);
    sim_wall += since(t1);
    r.min_rock_clearance = std::min(r.min_rock_clearance, shift.min_any_rock_clearance);
    out.min_rock_clearance = std::min(out.min_rock_clearance, r.min_rock_clearance);
    out.planned_advance += (next.translation() - body.translation()).dot(dir);
    body = next;
    q = q_next;
    r.body_after = body.translation();
    out.steps.push_back(std::move(r));
  }
  out.completed = out.reason.empty();
  out.body_end = sim.body_pose().translation();
  out.planning_seconds = plan_wall;
  out.simulated_seconds = sim.time() - sim_start;
  out.simulation_wall_seconds = sim_wall;
  return out;
}

}  // namespace ernest::walker_sim
