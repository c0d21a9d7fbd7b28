// Walker benchmark (target: IK of one leg ≤ 20 µs): microseconds per single-start IK solve of
// an SDM-B leg (LegIk::solve_from) for targets around the standard stance, seeded from the
// standard configuration; also the multi-start solve (every solution), forward kinematics with
// the contact Jacobian, and the static torques. Medians over repeats. The same-run reference (the
// same solve through numpy/scipy) is benchmarks/bench_walker.py, which `./run bench walker` runs
// next.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <vector>

#include "bench_util.hpp"
#include "ernest/walker/leg_ik.hpp"

using namespace ernest::walker;
using ernest::bench::Clock;
using ernest::bench::cpu_model;
using ernest::bench::median_us;

int main() {
  const WalkerModel model(sdm_b_parameters());
  const int n = model.joints_per_leg();
  const Eigen::VectorXd seed = model.standard_configuration().col(0);
  // Targets: the standard leg pose with every joint moved by up to ±0.3 rad (a step's reach).
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> d(-0.3, 0.3);
  const int kTargets = 200;
  std::vector<Eigen::Isometry3d> targets;
  for (int k = 0; k < kTargets; ++k) {
    Eigen::VectorXd q = seed;
    for (int i = 0; i < n; ++i) q[i] += d(rng);
    q = q.cwiseMax(model.lower_limits()).cwiseMin(model.upper_limits());
    targets.push_back(model.foot_pose(0, q));
  }
  LegIk ik(model);
  Eigen::VectorXd q(n);
  int solved = 0, evaluations = 0;
  for (const auto& t : targets) {
    solved += ik.solve_from(0, t, seed, q);
    evaluations += ik.last_evaluations();
  }
  const double single = median_us([&] { for (const auto& t : targets) ik.solve_from(0, t, seed, q); },
                                  kTargets, 15);
  std::printf("SDM-B leg IK, %d targets within ±0.3 rad of the standard stance, seed = standard\n",
              kTargets);
  std::printf("  solve_from (one start):       %8.2f us   (%d/%d converged, %.1f evaluations mean)\n",
              single, solved, kTargets, double(evaluations) / kTargets);
  int found = 0;
  const double multi = median_us([&] {
    found = 0;
    for (int k = 0; k < 20; ++k) found += int(ik.solve(0, targets[k], seed).solutions.size());
  }, 20, 5);
  std::printf("  solve (%d starts, all solutions): %8.2f us   (%.2f solutions per target)\n",
              ik.options().seeds, multi, found / 20.0);
  LegWorkspace ws(model);
  Eigen::Matrix3Xd J(3, n);
  Eigen::VectorXd tau(n);
  const Eigen::Vector3d g = model.gravity_in_body(Eigen::Matrix3d::Identity());
  const double fk = median_us([&] {
    for (int k = 0; k < 1000; ++k) {
      model.forward(k % 6, seed, ws);
      model.contact_jacobian(ws, J);
      model.joint_torques(ws, Eigen::Vector3d(0, 0, 1400.0), g, tau);
    }
  }, 1000, 15);
  std::printf("  forward + contact Jacobian + torques: %8.3f us\n", fk);
  return 0;
}
