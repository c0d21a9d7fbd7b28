// A small wrapper around NLopt's SLSQP (seed 000 §5: "NLOPT ... SLSQP ... maximum time of 0.5 s")
// that never lets a C++ exception cross NLopt's C callbacks.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace ernest::opt {

/// Stopping criteria. SLSQP misbehaves without tolerances, so all of them are always set.
struct SolverOptions {
  double max_time = 0.5;       ///< wall-clock budget [s] (paper: 0.5 s)
  double xtol_rel = 1e-7;      ///< relative step tolerance
  double ftol_rel = 1e-9;      ///< relative objective tolerance
  double ftol_abs = 1e-12;     ///< absolute objective tolerance
  int max_eval = 2000;         ///< objective evaluations
  double constraint_tol = 1e-8;  ///< feasibility tolerance of each constraint
  void validate() const;
};

/// f(x, grad): returns the objective; fills grad[0..n) when grad != nullptr.
using ObjectiveFunction = std::function<double(const double* x, double* grad)>;
/// c(x, result, jac): fills result[0..m) (feasible when <= 0 for inequalities, == 0 for equalities)
/// and, when jac != nullptr, the m x n Jacobian row-major.
using ConstraintFunction = std::function<void(const double* x, double* result, double* jac)>;

struct VectorConstraint {
  int size = 0;
  ConstraintFunction function;
};

/// min f(x) s.t. lower <= x <= upper, inequality(x) <= 0, equality(x) = 0.
struct OptimizationProblem {
  int dimension = 0;
  ObjectiveFunction objective;
  std::vector<double> lower, upper;  ///< empty = unbounded
  std::vector<VectorConstraint> inequality, equality;
};

struct SolverResult {
  std::vector<double> x;    ///< best point returned by NLopt
  double value = 0.0;       ///< objective at x
  int status = 0;           ///< nlopt_result code (negative = failure)
  std::string status_name;  ///< e.g. "XTOL_REACHED", "MAXTIME_REACHED", "ROUNDOFF_LIMITED"
  int evaluations = 0;      ///< objective evaluations
  double seconds = 0.0;     ///< wall-clock time of the solve
  /// True for NLopt's success codes, including MAXTIME/MAXEVAL (a usable, maybe suboptimal x).
  bool converged() const { return status > 0; }
};

/// Runs NLopt LD_SLSQP from x0. The time budget is kept by NLopt's max_time and, because NLopt only
/// checks it after an evaluation, by stopping before an iteration that is predicted (from the
/// longest iteration so far) to end past the budget; the result is then MAXTIME_REACHED with NLopt's
/// best point. An exception thrown by the objective or a constraint is captured,
/// the run is stopped with force_stop(), and the same exception (same type) is rethrown here.
/// Throws std::invalid_argument on an ill-formed problem.
SolverResult minimize_slsqp(const OptimizationProblem& problem, std::vector<double> x0,
                            const SolverOptions& options = {});

/// Name of an nlopt_result code ("SUCCESS", "FORCED_STOP", ...).
std::string nlopt_status_name(int status);

}  // namespace ernest::opt
