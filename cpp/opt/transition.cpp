// Gait transitions (transition.hpp): names and Table 1's weights, the options and the problem
// checked, the result evaluated along the three phases (g1, the transition, g2 shifted, eq 3),
// and the Naive strategy (a synchronised trapezoid). The optimised strategies:
// transition_optimise.cpp (SLSQP) over transition_cost.hpp (decision vector, eq 8, limits).
#include "ernest/opt/transition.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "ernest/common/validation.hpp"

namespace ernest::opt {

// ---------------------------------------------------------------------------------------------
// Names, weights, options, problem

std::string to_string(Strategy s) {
  switch (s) {
    case Strategy::Naive: return "naive";
    case Strategy::Bezier: return "bezier";
    case Strategy::Linear: return "linear";
    case Strategy::Spline: return "spline";
  }
  return "unknown";
}

std::string to_string(WeightSet w) {
  switch (w) {
    case WeightSet::Duration: return "duration";
    case WeightSet::Deviation: return "deviation";
    case WeightSet::Balanced: return "balanced";
  }
  return "unknown";
}

Strategy strategy_from_string(const std::string& name) {
  for (Strategy s : {Strategy::Naive, Strategy::Bezier, Strategy::Linear, Strategy::Spline})
    if (to_string(s) == name) return s;
  throw std::invalid_argument("unknown strategy '" + name + "'; allowed: naive, bezier, linear, spline");
}

WeightSet weight_set_from_string(const std::string& name) {
  for (WeightSet w : {WeightSet::Duration, WeightSet::Deviation, WeightSet::Balanced})
    if (to_string(w) == name) return w;
  throw std::invalid_argument("unknown weight set '" + name +
                              "'; allowed: duration, deviation, balanced");
}

void CostWeights::validate() const {
  require_in_range("CostWeights", "duration", duration, 0.0, 1e6);
  require_in_range("CostWeights", "acceleration", acceleration, 0.0, 1e6);
  require_in_range("CostWeights", "deviation", deviation, 0.0, 1e6);
  require_in_range("CostWeights", "linear", linear, 0.0, 1e6);
}

CostWeights CostWeights::table1(Strategy strategy, WeightSet set) {
  // Table 1 of seed 000: w1 (duration), w2 (acceleration), w3 (workspace deviation).
  CostWeights w;
  if (strategy == Strategy::Bezier) {
    if (set == WeightSet::Duration) w = {30.0, 1.0, 1.0, 1.0};
    if (set == WeightSet::Deviation) w = {1.0, 1.0, 20.0, 1.0};
    if (set == WeightSet::Balanced) w = {5.0, 1.0, 1.0, 1.0};
  } else if (strategy == Strategy::Linear || strategy == Strategy::Spline) {
    if (set == WeightSet::Duration) w = {20.0, 5.0, 1.0, 1.0};
    if (set == WeightSet::Deviation) w = {4.0, 5.0, 20.0, 1.0};
    if (set == WeightSet::Balanced) w = {4.0, 5.0, 1.0, 1.0};
  }
  return w;
}

void TransitionOptions::validate() const {
  solver.validate();
  constexpr const char* o = "TransitionOptions";
  require_in_range(o, "waypoints", waypoints, 3, 2000);
  require_in_range(o, "min_duration", min_duration, 1e-3, 1e4);
  require_in_range(o, "max_duration", max_duration, min_duration, 1e4);
  require_positive(o, "duration_scale", duration_scale);
  require_positive(o, "acceleration_scale", acceleration_scale);
  require_positive(o, "position_scale", position_scale);
  require_positive(o, "heading_scale", heading_scale);
  require_positive(o, "linear_scale", linear_scale);
  require_in_range(o, "initial_durations", initial_durations, 1, 1000);
  require_in_range(o, "initial_phases", initial_phases, 1, 1000);
  require_in_range(o, "limit_margin", limit_margin, 0.0, 0.1);
  require_in_range(o, "feasibility_tol", feasibility_tol, 0.0, 1.0);
  integration.validate();
}

TransitionProblem::TransitionProblem(const AsterixParameters& rover_, Gait from_, Gait to_,
                                     double t1_)
    : rover(rover_), from(std::move(from_)), to(std::move(to_)), t1(t1_) {
  require(from.joints() == kAsterixJoints,
          "TransitionProblem: limits from the rover need two-joint gaits (steering, roll)");
  position_limit = rover.position_limit();
  velocity_limit = rover.velocity_limit();
  acceleration_limit = rover.acceleration_limit();
  validate();
}

TransitionProblem::TransitionProblem(const AsterixParameters& rover_, Gait from_, Gait to_,
                                     double t1_, Eigen::VectorXd position_limit_,
                                     Eigen::VectorXd velocity_limit_,
                                     Eigen::VectorXd acceleration_limit_)
    : rover(rover_),
      from(std::move(from_)),
      to(std::move(to_)),
      t1(t1_),
      position_limit(std::move(position_limit_)),
      velocity_limit(std::move(velocity_limit_)),
      acceleration_limit(std::move(acceleration_limit_)) {
  validate();
}

void TransitionProblem::validate() const {
  rover.validate();
  require_finite("TransitionProblem", "t1", t1);
  const int n = from.joints();
  require(to.joints() == n, "TransitionProblem: both gaits need the same number of joints");
  require(position_limit.size() == n && velocity_limit.size() == n &&
              acceleration_limit.size() == n,
          "TransitionProblem: limits need one entry per joint");
  for (int j = 0; j < n; ++j) {
    require_positive("TransitionProblem", "position_limit", position_limit[j]);
    require_positive("TransitionProblem", "velocity_limit", velocity_limit[j]);
    require_positive("TransitionProblem", "acceleration_limit", acceleration_limit[j]);
  }
  // The steering joint enters tan(theta/2) (eq 22): keep it well inside +-pi.
  require(position_limit[kSteering] < 2.5,
          "TransitionProblem: position_limit[0] (steering) must be < 2.5 rad");
  from.check_limits(position_limit, velocity_limit);
  to.check_limits(position_limit, velocity_limit);
}

int TransitionResult::joints() const {
  return strategy == Strategy::Naive ? trapezoid.joints() : spline.joints();
}

void TransitionResult::evaluate(int j, double tau, double& q, double& dq, double& ddq) const {
  if (strategy == Strategy::Naive)
    trapezoid.evaluate(j, tau, q, dq, ddq);
  else
    spline.evaluate(j, tau, q, dq, ddq);
}

void TransitionResult::peaks(int j, double& position, double& velocity) const {
  if (strategy != Strategy::Naive) return spline.max_abs(j, position, velocity);
  // The trapezoid moves monotonically between its ends at |q̇| <= its cruise speed.
  double q0, q1, dq, ddq;
  trapezoid.evaluate(j, 0.0, q0, dq, ddq);
  trapezoid.evaluate(j, trapezoid.duration(), q1, dq, ddq);
  position = std::max(std::abs(q0), std::abs(q1));
  velocity = trapezoid.cruise_velocity(j);
}

void TransitionResult::executed(const TransitionProblem& problem, int j, double t, double& q,
                                double& dq, double& ddq) const {
  if (t < t1)
    problem.from.evaluate(j, t, q, dq, ddq);
  else if (t > t1 + duration)
    problem.to.evaluate(j, t - phase_shift, q, dq, ddq);  // g2(t - phi), eq 3
  else
    evaluate(j, t - t1, q, dq, ddq);
}

// ---------------------------------------------------------------------------------------------
// Naive

TransitionResult naive_transition(const TransitionProblem& problem) {
  problem.validate();
  const auto start = std::chrono::steady_clock::now();
  TransitionResult r;
  r.requested = r.strategy = Strategy::Naive;
  r.t1 = problem.t1;
  r.trapezoid = TrapezoidTrajectory(problem.from.position(problem.t1), problem.to.position(0.0),
                                    problem.velocity_limit, problem.acceleration_limit);
  r.duration = r.trapezoid.duration();
  // Continue with g2 from phase 0: g2(t - phi) at t = t1 + T is g2(0), so phi = t1 + T.
  r.phase_shift = problem.t1 + r.duration;
  r.end_phase = 0.0;
  r.solver.status_name = "NOT_OPTIMISED";
  r.max_violation = -kInf;
  for (int j = 0; j < problem.joints(); ++j) {
    double q, v;
    r.peaks(j, q, v);
    r.max_violation = std::max({r.max_violation, q / problem.position_limit[j] - 1.0,
                                v / problem.velocity_limit[j] - 1.0});
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace ernest::opt
