// Walker in ODE (execution in simulation): wall time to simulate one gait cycle of
// FootFall's skeleton gait (cpp/walker/gait_planner: six steps through the compliance waypoints and
// six body shifts, SDM-B, flat ground) against the simulated time (the reference: real time).
// Medians over repeats, each from a fresh simulator settled on its six wheels (not timed). The
// process CPU time is printed too: on a shared, overloaded machine the wall time mostly measures
// the queue.
#include <time.h>

#include <cstdio>
#include <vector>
#include <algorithm>

#include "bench_util.hpp"
#include "ernest/walker_sim/gait_execution.hpp"

using namespace ernest;

namespace {
double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
}  // namespace

int main() {
  const walker::WalkerModel model(walker::sdm_b_parameters());
  walker::GaitPlannerOptions go;
  go.cycles = 1;
  const walker::GaitPlan plan =
      walker::plan_gait(model, model.standard_body_pose().translation(), model.standard_configuration(), go);
  const walker_sim::WalkerSimOptions so;
  const walker_sim::ExecutionOptions eo;
  const int kRepeats = 3;
  std::vector<double> wall, ratio, cpu, cpu_ratio;
  walker_sim::GaitExecution last;
  for (int r = 0; r < kRepeats; ++r) {
    walker_sim::WalkerSim sim(model, model.standard_body_pose(), model.standard_configuration(), {}, so);
    sim.hold(model.standard_configuration(), 1.0);
    const double c0 = cpu_seconds();
    last = walker_sim::execute_gait_cycle(sim, plan, 0, eo);
    cpu.push_back(cpu_seconds() - c0);
    cpu_ratio.push_back(cpu.back() / last.simulated_seconds);
    wall.push_back(last.wall_seconds);
    ratio.push_back(last.wall_seconds / last.simulated_seconds);
  }
  std::printf("Walker in ODE (SDM-B, %d bodies, dt = %.4f s), one gait cycle (%d steps, %d shifts), %s\n",
              1 + model.legs() * model.joints_per_leg(), so.dt, last.steps, last.shifts,
              bench::cpu_model().c_str());
  std::printf("  simulated time per cycle:        %8.2f s (joint speed %.2f rad/s, %.2f s pauses)\n",
              last.simulated_seconds, eo.joint_speed, eo.pause);
  std::printf("  wall time per cycle (median/%d): %8.2f s   CPU time %8.2f s\n", kRepeats, median(wall),
              median(cpu));
  std::printf("  ratio to real time (median):     %8.3f wall, %.3f CPU   (< 1: faster than real time)\n",
              median(ratio), median(cpu_ratio));
  std::printf("  per physics step:                %8.1f us wall, %.1f us CPU\n",
              1e6 * median(wall) / (last.simulated_seconds / so.dt), 1e6 * median(cpu) / (last.simulated_seconds / so.dt));
  std::printf("  body advance: %.3f m simulated, %.3f m planned; swing wheels >= %.3f m over the ground\n",
              (last.body_end - last.body_start).x(), last.planned_advance, last.min_ground_clearance);
  return 0;
}
