#include "ernest/walker_sim/gait_execution.hpp"

#include <algorithm>
#include <chrono>
#include <string>

#include "ernest/common/validation.hpp"

namespace ernest::walker_sim {

GaitExecution execute_gait_cycle(WalkerSim& sim, const walker::GaitPlan& plan, int cycle,
                                 const ExecutionOptions& options) {
  options.validate();
  const auto t0 = std::chrono::steady_clock::now();
  GaitExecution out;
  out.min_ground_clearance = kInf;
  out.body_start = sim.body_pose().translation();
  const double sim_start = sim.time();
  for (const walker::GaitEvent& e : plan.events) {
    if (e.cycle != cycle) continue;
    if (e.kind == walker::GaitEvent::kStep) {
      const std::vector<Eigen::VectorXd> path{e.q_before.col(e.leg), e.q_lift_start, e.q_lift_goal,
                                              e.q_after.col(e.leg)};
      const ExecutionTrace t = execute_joint_path(sim, e.leg, e.q_before, path, options);
      out.min_ground_clearance = std::min(out.min_ground_clearance, t.min_ground_clearance);
      ++out.steps;
    } else {
      execute_configuration_path(sim, std::nullopt, {e.q_before, e.q_after}, options);
      out.planned_advance += (e.body_after - e.body_before).norm();
      ++out.shifts;
    }
  }
  require(out.steps + out.shifts > 0, "execute_gait_cycle: the plan has no cycle " + std::to_string(cycle));
  out.body_end = sim.body_pose().translation();
  out.simulated_seconds = sim.time() - sim_start;
  out.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace ernest::walker_sim
