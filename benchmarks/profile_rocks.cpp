// Driver for instruction-count profiles of the rock scenarios: one rover rolling at
// 0.15 m/s on M90 (friction 0.8 on the rocks) into box rocks read from a file, as
// bench_dynamics.py's rolling_rover; the 50 steps of run-up are not counted (callgrind's
// collection is switched on after them when run with --collect-atstart=no and
// --toggle-collect=profiled_steps). REPEATS > 1 restores the state after the run-up and runs the
// STEPS again, as bench_dynamics.py does: long enough for a time profile with
//   perf record -e cpu-clock -F 20000 -g build/bench/benchmarks/profile_rocks /tmp/rocks20.txt 800 1 1 1 200
// SKIP steps more of run-up profile a later stretch (e.g. 240: the first rock contact among 20).
// CONTACT chooses SimOptions::wheel_obstacle_contact (exact|ode; default: the option's default),
// DT_DIVISOR divides SimOptions::dt (and multiplies every step count: the same simulated time);
// RESOLVE sets SimOptions::resolve_rhs_only (0|1; default on).
// Prints the solver's counts.
//   python benchmarks/bench_rocks.py --dump-rocks 20 /tmp/rocks20.txt
//   valgrind --tool=callgrind --collect-atstart=no --toggle-collect='*profiled_steps*' \
//       build/bench/benchmarks/profile_rocks /tmp/rocks20.txt 400 8
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "ernest/dynamics/rover_sim.hpp"

using namespace ernest::dynamics;

// Not inlined: callgrind switches collection on and off at its entry and exit.
__attribute__((noinline)) void profiled_steps(RoverSim& sim, int steps) { sim.step_n(steps); }

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: profile_rocks ROCKS_FILE STEPS SUBSTEPS [guess 0|1] [slip_warm_start 0|1] [REPEATS] [SKIP] [stepper ode|own] [contact exact|ode] [DT_DIVISOR] [RESOLVE 0|1]\n");
    return 2;
  }
  std::vector<BoxObstacle> rocks;
  std::ifstream in(argv[1]);
  double cx, cy, cz, sx, sy, sz, yaw;
  while (in >> cx >> cy >> cz >> sx >> sy >> sz >> yaw)
    rocks.push_back({Eigen::Vector3d(cx, cy, cz), Eigen::Vector3d(sx, sy, sz), yaw, 0.0, 0.0});
  SimOptions o;
  o.friction = 0.8;
  o.obstacle_substeps = std::atoi(argv[3]);
  o.guess_obstacle_contacts = argc < 5 || std::atoi(argv[4]) != 0;
  o.slip_warm_start = argc < 6 || std::atoi(argv[5]) != 0;
  // STEPPER: who steps the bodies (SimOptions::stepper; default: the option's default)
  if (argc >= 9) o.stepper = std::string(argv[8]) == "own" ? Stepper::Own : Stepper::Ode;
  if (argc >= 10)
    o.wheel_obstacle_contact = std::string(argv[9]) == "ode" ? WheelObstacleContact::Ode
                                                             : WheelObstacleContact::Exact;
  const int divisor = argc >= 11 ? std::max(1, std::atoi(argv[10])) : 1;
  o.dt /= divisor;
  if (argc >= 12) o.resolve_rhs_only = std::atoi(argv[11]) != 0;
  const double speed = 0.15;
  RoverSim sim(RoverParameters{}, HeightMap::flat(40, 20, 0.25, 0, -10, -10), rocks, o);
  sim.reset(0, 0, 0, 0, 0, speed);
  Commands c;
  for (auto& w : c.wheel_speed) w = speed / sim.parameters().wheel_radius;
  sim.set_commands(c);
  sim.step_n(divisor * (50 + (argc < 8 ? 0 : std::atoi(argv[7]))));
  const Snapshot start = sim.snapshot();
  const int repeats = argc < 7 ? 1 : std::max(1, std::atoi(argv[6]));
  for (int r = 0; r < repeats; ++r) {
    if (r > 0) sim.restore(start);
    profiled_steps(sim, divisor * std::atoi(argv[2]));
  }
  const SolverStats& s = sim.solver_stats();
  std::printf("%zu rocks: x %.4f m; solves sparse %llu dense %llu; obstacle (sub)steps guessed %llu "
              "bounded %llu; slip solves %llu, driving %llu; guesses first %llu later %llu "
              "pivoted %llu; contacts explicit %llu implicit %llu; own steps %llu fallbacks %llu rhs %llu caps %llu; plans made %llu grown %llu; state x %.17g z %.17g vx %.17g\n",
              rocks.size(), sim.state().position.x(), (unsigned long long)s.sparse_solves,
              (unsigned long long)s.dense_solves, (unsigned long long)s.obstacle_guessed,
              (unsigned long long)s.obstacle_bounded, (unsigned long long)s.slip_solves,
              (unsigned long long)s.slip_driving, (unsigned long long)s.first_guess,
              (unsigned long long)s.later_guess, (unsigned long long)s.pivoted,
              (unsigned long long)s.obstacle_explicit, (unsigned long long)s.obstacle_implicit,
              (unsigned long long)s.own_steps, (unsigned long long)s.own_fallbacks, (unsigned long long)s.rhs_resolves, (unsigned long long)s.cap_resolves,
              (unsigned long long)s.plans_made, (unsigned long long)s.plans_grown, sim.state().position.x(),
              sim.state().position.z(), sim.state().linear_velocity.x());
  return 0;
}
