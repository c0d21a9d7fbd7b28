// Walker in ODE (issue 16, execution in simulation): wall time to simulate one gait cycle of
// FootFall's skeleton gait (cpp/walker/gait_planner: six steps through the compliance waypoints and
// six body shifts, SDM-B, flat ground) against the simulated time (the reference: real time).
// Medians over repeats, each from a fresh simulator settled on its six wheels (not timed).
#include <cstdio>
#include <vector>
#include <algorithm>

#include "bench_util.hpp"
#include "ernest/walker_sim/gait_execution.hpp"

using namespace ernest;

int main() {
  const walker::WalkerModel model(walker::sdm_b_parameters());
  walker::GaitPlannerOptions go;
  go.cycles = 1;
  const walker::GaitPlan plan =
      walker::plan_gait(model, model.standard_body_pose().translation(), model.standard_configuration(), go);
  const walker_sim::WalkerSimOptions so;
  const walker_sim::ExecutionOptions eo;
  const int kRepeats = 3;
  std::vector<double> wall, ratio;
  walker_sim::GaitExecution last;
  for (int r = 0; r < kRepeats; ++r) {
    walker_sim::WalkerSim sim(model, model.standard_body_pose(), model.standard_configuration(), {}, so);
    sim.hold(model.standard_configuration(), 1.0);
    last = walker_sim::execute_gait_cycle(sim, plan, 0, eo);
    wall.push_back(last.wall_seconds);
    ratio.push_back(last.wall_seconds / last.simulated_seconds);
  }
  std::sort(wall.begin(), wall.end());
  std::sort(ratio.begin(), ratio.end());
  std::printf("Walker in ODE (SDM-B, %d bodies, dt = %.4f s), one gait cycle (%d steps, %d shifts), %s\n",
              1 + model.legs() * model.joints_per_leg(), so.dt, last.steps, last.shifts,
              bench::cpu_model().c_str());
  std::printf("  simulated time per cycle:        %8.2f s (joint speed %.2f rad/s, %.2f s pauses)\n",
              last.simulated_seconds, eo.joint_speed, eo.pause);
  std::printf("  wall time per cycle (median/%d): %8.2f s\n", kRepeats, wall[wall.size() / 2]);
  std::printf("  ratio wall / simulated (median): %8.3f   (< 1: faster than real time)\n", ratio[ratio.size() / 2]);
  std::printf("  per physics step:                %8.1f us\n",
              1e6 * wall[wall.size() / 2] / (last.simulated_seconds / so.dt));
  std::printf("  body advance: %.3f m simulated, %.3f m planned; swing wheels >= %.3f m over the ground\n",
              (last.body_end - last.body_start).x(), last.planned_advance, last.min_ground_clearance);
  return 0;
}
