// Gait transitions of seed 000 §3–4: Naive, Bezier (eqs 9–13), Linear (eqs 14–19) and Spline,
// optimised with NLopt SLSQP under a wall-clock budget, cost eq 8 with the Table 1 weights.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ernest/opt/asterix_model.hpp"
#include "ernest/opt/gait.hpp"
#include "ernest/opt/nlopt_solver.hpp"
#include "ernest/opt/trajectory.hpp"

namespace ernest::opt {

enum class Strategy { Naive, Bezier, Linear, Spline };
/// The three weight distributions of Table 1.
enum class WeightSet { Duration, Deviation, Balanced };

std::string to_string(Strategy s);
std::string to_string(WeightSet w);
Strategy strategy_from_string(const std::string& name);
WeightSet weight_set_from_string(const std::string& name);

/// Weights of cost eq 8: w1 T + w2 (acceleration) + w3 (workspace deviation), plus the linear
/// cost of eqs 18–19 (used by Linear only; its weight is not given in the paper: ours, 1).
struct CostWeights {
  double duration = 5.0;      ///< w1
  double acceleration = 1.0;  ///< w2
  double deviation = 1.0;     ///< w3
  double linear = 1.0;        ///< weight of eq 19 (Linear strategy only)
  void validate() const;
  /// Table 1 of seed 000 (Bezier: 30/1/1, 1/1/20, 5/1/1; Linear and Spline: 20/5/1, 4/5/20,
  /// 4/5/1). Naive has no weights (returns the defaults).
  static CostWeights table1(Strategy strategy, WeightSet set);
};

/// Options of the optimised strategies. Each term of eq 8 is normalised so that SLSQP sees
/// quantities of order one:
///   duration      T / duration_scale
///   acceleration  (1/T) ∫ sum_j (q̈_j / acceleration_scale)^2 dt   (mean squared; the paper's
///                 "sum of the second derivative", squared so it is smooth and sign-free)
///   deviation     (|Δp| / position_scale)^2 + (Δψ / heading_scale)^2, Δ = x(t1+T) minus the
///                 eq 7 target, both relative to G1(t1) (eq 6 holds by construction)
///   linear        (1/N) sum_t sum_j ((θ_t,j − l_j(t)) / linear_scale)^2  (eq 19, squared)
struct TransitionOptions {
  SolverOptions solver;            ///< SLSQP tolerances and the 0.5 s budget (max_time)
  int waypoints = 100;             ///< Linear/Spline waypoints per joint (paper: 100)
  double min_duration = 0.2;       ///< bounds on T [s]
  double max_duration = 30.0;
  double duration_scale = 1.0;     ///< [s]
  double acceleration_scale = 1.0; ///< [rad/s^2]
  double position_scale = 0.02;    ///< [m]
  double heading_scale = 0.05;     ///< [rad]
  double linear_scale = 0.1;       ///< [rad]
  int initial_durations = 10;      ///< grid of the initial search over (T, end phase)
  int initial_phases = 24;
  /// SLSQP sees the joint limits tightened by this fraction (exact rows: |q| / P <= 1 - margin):
  /// its converged point is feasible only to its own constraint_tol, and the returned transition
  /// must never exceed the true limits (it is rejected if it does).
  double limit_margin = 1e-7;
  double feasibility_tol = 1e-6;   ///< accepted normalised violation of eq 17's rows and the bounds
  bool fallback = true;            ///< on failure use Naive (reason reported) instead of throwing
  IntegrationOptions integration{1e-9, 1e-8, 200000};
  void validate() const;
};

/// One transition from gait `from` at time t1 to gait `to` (eqs 2–7). Joint limits are symmetric
/// (|q_j| <= position_limit_j, eq 16; |q̇_j| <= velocity_limit_j, eq 17); the acceleration limit
/// shapes the Naive trapezoid. Joint 0 is the steering joint that drives the kinematics.
struct TransitionProblem {
  AsterixParameters rover;
  Gait from, to;
  double t1 = 0.0;
  Eigen::VectorXd position_limit, velocity_limit, acceleration_limit;

  /// Limits taken from the rover (two joints: steering, roll).
  TransitionProblem(const AsterixParameters& rover, Gait from, Gait to, double t1);
  TransitionProblem(const AsterixParameters& rover, Gait from, Gait to, double t1,
                    Eigen::VectorXd position_limit, Eigen::VectorXd velocity_limit,
                    Eigen::VectorXd acceleration_limit);
  int joints() const { return from.joints(); }
  void validate() const;
};

struct TransitionResult {
  Strategy requested = Strategy::Naive;
  Strategy strategy = Strategy::Naive;  ///< what was returned (Naive after a fallback)
  CostWeights weights;
  bool fell_back = false;
  std::string fallback_reason;          ///< why the optimised result was rejected
  double t1 = 0.0;
  double duration = 0.0;                ///< T
  double phase_shift = 0.0;             ///< φ of eq 3: g2 continues as g2(t − φ)
  double end_phase = 0.0;               ///< t1 + T − φ, the phase of g2 reached at the end
  SplineTrajectory spline;              ///< Bezier / Linear / Spline
  TrapezoidTrajectory trapezoid;        ///< Naive
  SolverResult solver;                  ///< SLSQP result (status, evaluations, seconds)
  double seconds = 0.0;                 ///< total wall-clock time incl. the initial search
  double cost = 0.0;                    ///< eq 8 (weighted sum) of the returned optimised solution
  double cost_duration = 0.0, cost_acceleration = 0.0, cost_deviation = 0.0, cost_linear = 0.0;
  /// Exact largest normalised joint-limit violation along the transition (eqs 16–17, <= 0 when
  /// feasible): max over joints and over the whole curve of |q| / P - 1 and |q̇| / V - 1, from the
  /// analytic extrema of its cubic segments (Naive: its trapezoid's end positions and cruise speed).
  double max_violation = 0.0;
  int joints() const;
  /// Transition position/velocity/acceleration of joint j at tau in [0, T] after t1.
  void evaluate(int j, double tau, double& q, double& dq, double& ddq) const;
  /// Exact max over the transition of |q_j| and |q̇_j| (analytic extrema, not samples).
  void peaks(int j, double& position, double& velocity) const;
  /// Joint j of the executed motion at absolute time t: g1 before t1, the transition, then
  /// g2(t − φ).
  void executed(const TransitionProblem& problem, int j, double t, double& q, double& dq,
                double& ddq) const;
};

/// Plans one transition. Optimised strategies run SLSQP for at most options.solver.max_time seconds
/// in total (initial search included). Non-finite, infeasible or failed results — including an
/// exception inside the cost or the kinematics — fall back to Naive with the reason reported
/// (or are rethrown when options.fallback is false).
TransitionResult plan_transition(const TransitionProblem& problem, Strategy strategy,
                                 const CostWeights& weights = {},
                                 const TransitionOptions& options = {});

/// Size of the decision vector x = [T, sigma, interior waypoints (joint-major)] of an optimised
/// strategy (sigma = t1 + T - phi is the end phase of g2).
int transition_dimension(const TransitionProblem& problem, Strategy strategy,
                         const TransitionOptions& options = {});
/// Cost eq 8 of an optimised strategy at x and, when grad != nullptr, its analytic gradient
/// (exposed for tests and diagnostics).
double transition_cost(const TransitionProblem& problem, Strategy strategy,
                       const CostWeights& weights, const TransitionOptions& options,
                       const std::vector<double>& x, std::vector<double>* grad = nullptr);
/// The inequality constraints (<= 0) at x and, when jacobian != nullptr, their m x n Jacobian
/// (row-major).
void transition_constraints(const TransitionProblem& problem, Strategy strategy,
                            const TransitionOptions& options, const std::vector<double>& x,
                            std::vector<double>& values, std::vector<double>* jacobian = nullptr);

/// The Naive transition (trapezoidal move from g1(t1) to g2(0), then g2 from phase 0).
TransitionResult naive_transition(const TransitionProblem& problem);

}  // namespace ernest::opt
