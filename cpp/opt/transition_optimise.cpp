// The optimised gait transitions (Bezier, Linear, Spline; seed 000 §4–5): an initial search over
// (T, end phase) on the two-point Bezier, then NLopt SLSQP under the wall-clock budget, the
// answer checked against the exact limits; plan_transition falls back to Naive on failure.
// transition_cost/_constraints/_dimension expose the cost for tests and plots.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlopt.h>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"
#include "ernest/opt/transition.hpp"
#include "ernest/opt/transition_cost.hpp"

namespace ernest::opt {

namespace {

using detail::TransitionCost;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

TransitionResult optimise(const TransitionProblem& problem, Strategy strategy,
                          const CostWeights& weights, const TransitionOptions& options,
                          std::chrono::steady_clock::time_point start) {
  const int n = strategy == Strategy::Bezier ? 2 : options.waypoints;
  TransitionCost cost(problem, strategy, weights, options, n);
  const int dim = cost.dimension();
  const double budget = options.solver.max_time;
  const double P2 = problem.to.period();

  // Initial search over (T, end phase) on the two-point Bezier shape (shared by all strategies),
  // using at most 40% of the budget.
  std::vector<double> lo(dim), hi(dim);
  lo[0] = options.min_duration;
  hi[0] = options.max_duration;
  lo[1] = -kInf;
  hi[1] = kInf;
  for (int j = 0; j < problem.joints(); ++j)
    for (int i = 1; i < n - 1; ++i) {
      lo[cost.index(j, i)] = -problem.position_limit[j];
      hi[cost.index(j, i)] = problem.position_limit[j];
    }
  std::vector<double> best;
  double best_score = kInf;
  const double t_lo = std::max(options.min_duration, 0.25);
  const double t_hi = std::min(options.max_duration, 12.0);
  const int nt = options.initial_durations, np = options.initial_phases;
  bool out_of_time = false;
  double longest_eval = 0.0;  // of one candidate (constraints + cost without gradient)
  for (int a = 0; a < nt && !out_of_time; ++a) {
    const double T = nt == 1 ? t_lo : t_lo * std::pow(t_hi / t_lo, a / (nt - 1.0));
    for (int b = 0; b < np; ++b) {
      const double sigma = P2 * b / np;
      poll_interrupt();  // Ctrl-C between candidates (common/interrupt.hpp)
      const auto t_eval = std::chrono::steady_clock::now();
      std::vector<double> x = cost.bezier_guess(T, sigma);
      const double viol = cost.max_violation(x, lo, hi);
      double score;
      if (viol > options.feasibility_tol) {
        score = 1e12 + viol;
      } else {
        try {
          score = cost.objective(x.data(), nullptr);
        } catch (const KinematicsError&) {
          score = kInf;
        }
      }
      longest_eval = std::max(longest_eval, seconds_since(t_eval));
      if (std::isfinite(score) && score < best_score) {
        best_score = score;
        best = std::move(x);
      }
      if (seconds_since(start) > 0.4 * budget) {
        out_of_time = true;
        break;
      }
    }
  }
  if (best.empty()) throw std::runtime_error("initial search found no finite candidate");
  lo[1] = best[1] - P2;
  hi[1] = best[1] + P2;

  OptimizationProblem op;
  op.dimension = dim;
  op.lower = lo;
  op.upper = hi;
  op.objective = [&cost](const double* x, double* grad) { return cost.objective(x, grad); };
  op.inequality.push_back({cost.constraint_count(), [&cost](const double* x, double* c,
                                                            double* jac) {
                             cost.constraints(x, c, jac);
                           }});
  SolverOptions so = options.solver;
  // Keep time for the final check of SLSQP's point (one cost and constraint evaluation) and 2% of
  // the budget for scheduling jitter on shared machines.
  so.max_time = budget - seconds_since(start) - 2.0 * longest_eval - 0.02 * budget;
  SolverResult sr;
  if (so.max_time > 1e-4) {
    sr = minimize_slsqp(op, best, so);
  } else {
    sr.x = best;
    sr.value = best_score;
    sr.status = NLOPT_MAXTIME_REACHED;
    sr.status_name = "MAXTIME_REACHED";
  }
  for (double v : sr.x)
    if (!std::isfinite(v)) throw std::runtime_error("SLSQP returned a non-finite point");
  const double f = cost.objective(sr.x.data(), nullptr);
  if (!std::isfinite(f)) throw std::runtime_error("the cost is not finite at SLSQP's point");
  const double viol = cost.max_violation(sr.x, lo, hi);
  if (viol > options.feasibility_tol) {
    std::ostringstream os;
    os << "SLSQP point infeasible (max violation " << viol << ", status " << sr.status_name << ")";
    throw std::runtime_error(os.str());
  }
  const double limits = cost.limit_violation(sr.x);
  if (!(limits <= 0.0)) {
    std::ostringstream os;
    os << "SLSQP point exceeds a joint limit (exact normalised violation " << limits
       << ", status " << sr.status_name << ")";
    throw std::runtime_error(os.str());
  }
  if (sr.status < 0 && sr.status != NLOPT_ROUNDOFF_LIMITED)
    throw std::runtime_error("SLSQP failed with status " + sr.status_name);
  TransitionResult r = cost.build(sr.x, f);
  r.solver = sr;
  r.max_violation = limits;
  return r;
}

}  // namespace

int transition_dimension(const TransitionProblem& problem, Strategy strategy,
                         const TransitionOptions& options) {
  require(strategy != Strategy::Naive, "transition_dimension: Naive has no decision vector");
  const int n = strategy == Strategy::Bezier ? 2 : options.waypoints;
  return 2 + problem.joints() * (n - 2);
}

double transition_cost(const TransitionProblem& problem, Strategy strategy,
                       const CostWeights& weights, const TransitionOptions& options,
                       const std::vector<double>& x, std::vector<double>* grad) {
  problem.validate();
  weights.validate();
  options.validate();
  const int dim = transition_dimension(problem, strategy, options);
  require(static_cast<int>(x.size()) == dim, "transition_cost: x has the wrong size");
  for (std::size_t i = 0; i < x.size(); ++i)
    require_finite("transition_cost", ("x[" + std::to_string(i) + "]").c_str(), x[i]);
  // x[0] is the duration T [s]: the solver keeps it within these bounds; T = 0 would give an
  // infinite cost (1 / T^4) and a negative T an integration backwards in time.
  require_in_range("transition_cost", "x[0] (the duration [s], options.min_duration..max_duration)", x[0],
                   options.min_duration, options.max_duration);
  TransitionCost cost(problem, strategy, weights, options,
                      strategy == Strategy::Bezier ? 2 : options.waypoints);
  if (grad) grad->assign(dim, 0.0);
  return cost.objective(x.data(), grad ? grad->data() : nullptr);
}

void transition_constraints(const TransitionProblem& problem, Strategy strategy,
                            const TransitionOptions& options, const std::vector<double>& x,
                            std::vector<double>& values, std::vector<double>* jacobian) {
  problem.validate();
  options.validate();
  const int dim = transition_dimension(problem, strategy, options);
  require(static_cast<int>(x.size()) == dim, "transition_constraints: x has the wrong size");
  for (std::size_t i = 0; i < x.size(); ++i)
    require_finite("transition_constraints", ("x[" + std::to_string(i) + "]").c_str(), x[i]);
  // x[0] is the duration T [s]: the solver keeps it within these bounds; T = 0 would give an
  // infinite cost (1 / T^4) and a negative T an integration backwards in time.
  require_in_range("transition_constraints", "x[0] (the duration [s], options.min_duration..max_duration)", x[0],
                   options.min_duration, options.max_duration);
  TransitionCost cost(problem, strategy, CostWeights{}, options,
                      strategy == Strategy::Bezier ? 2 : options.waypoints);
  values.assign(cost.constraint_count(), 0.0);
  if (jacobian) jacobian->assign(static_cast<std::size_t>(cost.constraint_count()) * dim, 0.0);
  cost.constraints(x.data(), values.data(), jacobian ? jacobian->data() : nullptr);
}

TransitionResult plan_transition(const TransitionProblem& problem, Strategy strategy,
                                 const CostWeights& weights, const TransitionOptions& options) {
  problem.validate();
  weights.validate();
  options.validate();
  const auto start = std::chrono::steady_clock::now();
  if (strategy == Strategy::Naive) return naive_transition(problem);
  std::string reason;
  try {
    TransitionResult r = optimise(problem, strategy, weights, options, start);
    r.seconds = seconds_since(start);
    return r;
  } catch (const std::invalid_argument&) {
    throw;  // a bad problem or option is the caller's error, never a silent fallback
  } catch (const Interrupted&) {
    throw;  // Ctrl-C (common/interrupt.hpp) stops the caller, it is not a failed optimisation
  } catch (const std::exception& e) {
    if (!options.fallback) throw;
    reason = e.what();
  }
  TransitionResult r = naive_transition(problem);
  r.requested = strategy;
  r.weights = weights;
  r.fell_back = true;
  r.fallback_reason = to_string(strategy) + " failed: " + reason;
  r.seconds = seconds_since(start);
  return r;
}

}  // namespace ernest::opt
