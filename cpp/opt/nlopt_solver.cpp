// NLopt SLSQP behind a C++ interface (nlopt_solver.hpp): tolerances, the time budget, and
// exceptions in the callbacks captured and rethrown after NLopt returns.
#include "ernest/opt/nlopt_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <nlopt.hpp>
#include <stdexcept>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"

namespace ernest::opt {

void SolverOptions::validate() const {
  require_in_range("SolverOptions", "max_time", max_time, 1e-6, 1e6);
  require_in_range("SolverOptions", "xtol_rel", xtol_rel, 0.0, 1.0);
  require_in_range("SolverOptions", "ftol_rel", ftol_rel, 0.0, 1.0);
  require_in_range("SolverOptions", "ftol_abs", ftol_abs, 0.0, 1e10);
  require_in_range("SolverOptions", "max_eval", max_eval, 1, 1e9);
  require_in_range("SolverOptions", "constraint_tol", constraint_tol, 0.0, 1.0);
}

std::string nlopt_status_name(int status) {
  switch (status) {
    case NLOPT_FAILURE: return "FAILURE";
    case NLOPT_INVALID_ARGS: return "INVALID_ARGS";
    case NLOPT_OUT_OF_MEMORY: return "OUT_OF_MEMORY";
    case NLOPT_ROUNDOFF_LIMITED: return "ROUNDOFF_LIMITED";
    case NLOPT_FORCED_STOP: return "FORCED_STOP";
    case NLOPT_SUCCESS: return "SUCCESS";
    case NLOPT_STOPVAL_REACHED: return "STOPVAL_REACHED";
    case NLOPT_FTOL_REACHED: return "FTOL_REACHED";
    case NLOPT_XTOL_REACHED: return "XTOL_REACHED";
    case NLOPT_MAXEVAL_REACHED: return "MAXEVAL_REACHED";
    case NLOPT_MAXTIME_REACHED: return "MAXTIME_REACHED";
    default: return "UNKNOWN(" + std::to_string(status) + ")";
  }
}

namespace {

// Shared state of one solve: the callbacks below run inside NLopt's C code, so they must not throw.
struct SolveContext {
  const OptimizationProblem* problem = nullptr;
  nlopt::opt* opt = nullptr;
  std::exception_ptr error;
  int evaluations = 0;
  // Deadline: NLopt checks max_time only after an evaluation, so one SLSQP iteration (QP solve +
  // evaluation) can overrun it. We stop before an iteration that would not finish in time,
  // predicting its length by the longest interval between two objective calls so far.
  std::chrono::steady_clock::time_point start, last_call;
  double max_time = 0.0, longest_interval = 0.0;
  bool deadline_stop = false;
};

struct ConstraintContext {
  SolveContext* solve = nullptr;
  const VectorConstraint* constraint = nullptr;
};

double objective_trampoline(unsigned /*n*/, const double* x, double* grad, void* data) {
  auto* ctx = static_cast<SolveContext*>(data);
  if (ctx->error || ctx->deadline_stop) return HUGE_VAL;
  const auto now = std::chrono::steady_clock::now();
  if (ctx->evaluations > 0) {
    ctx->longest_interval = std::max(
        ctx->longest_interval, std::chrono::duration<double>(now - ctx->last_call).count());
    const double elapsed = std::chrono::duration<double>(now - ctx->start).count();
    if (elapsed + 2.0 * ctx->longest_interval > ctx->max_time) {  // 2x: shared-CPU jitter
      ctx->deadline_stop = true;  // NLopt keeps the best point found so far in x
      ctx->opt->force_stop();
      return HUGE_VAL;
    }
  }
  ctx->last_call = now;
  try {
    poll_interrupt();  // Ctrl-C (common/interrupt.hpp): captured, stopped and rethrown like any error
    ++ctx->evaluations;
    return ctx->problem->objective(x, grad);
  } catch (...) {
    ctx->error = std::current_exception();
    ctx->opt->force_stop();
    return HUGE_VAL;
  }
}

void constraint_trampoline(unsigned m, double* result, unsigned /*n*/, const double* x,
                           double* grad, void* data) {
  auto* ctx = static_cast<ConstraintContext*>(data);
  if (ctx->solve->error) {
    for (unsigned i = 0; i < m; ++i) result[i] = HUGE_VAL;
    return;
  }
  try {
    poll_interrupt();  // as in the objective: captured, stopped, rethrown
    ctx->constraint->function(x, result, grad);
  } catch (...) {
    ctx->solve->error = std::current_exception();
    ctx->solve->opt->force_stop();
    for (unsigned i = 0; i < m; ++i) result[i] = HUGE_VAL;
  }
}

}  // namespace

SolverResult minimize_slsqp(const OptimizationProblem& problem, std::vector<double> x0,
                            const SolverOptions& options) {
  options.validate();
  const int n = problem.dimension;
  require(n >= 1, "minimize_slsqp: dimension must be >= 1");
  require(static_cast<int>(x0.size()) == n, "minimize_slsqp: x0 must have `dimension` entries");
  require(static_cast<bool>(problem.objective), "minimize_slsqp: objective is not set");
  require(problem.lower.empty() || static_cast<int>(problem.lower.size()) == n,
          "minimize_slsqp: lower bounds must be empty or have `dimension` entries");
  require(problem.upper.empty() || static_cast<int>(problem.upper.size()) == n,
          "minimize_slsqp: upper bounds must be empty or have `dimension` entries");
  for (int i = 0; i < n; ++i) {
    require_finite("minimize_slsqp", "x0", x0[i]);
    const double lo = problem.lower.empty() ? -kInf : problem.lower[i];
    const double hi = problem.upper.empty() ? kInf : problem.upper[i];
    if (!(lo <= hi)) {  // NaN too; NLopt would say only "bounds i fail"
      throw std::invalid_argument("minimize_slsqp: lower[" + std::to_string(i) + "] = " +
                                  std::to_string(lo) + " must be <= upper[" + std::to_string(i) +
                                  "] = " + std::to_string(hi) + " (neither NaN)");
    }
    // NLopt requires a start inside the bounds.
    if (!problem.lower.empty()) x0[i] = std::max(x0[i], problem.lower[i]);
    if (!problem.upper.empty()) x0[i] = std::min(x0[i], problem.upper[i]);
  }
  for (const auto* group : {&problem.inequality, &problem.equality})
    for (const auto& c : *group)
      require(c.size >= 1 && static_cast<bool>(c.function),
              "minimize_slsqp: every constraint needs size >= 1 and a function");

  nlopt::opt opt(nlopt::LD_SLSQP, static_cast<unsigned>(n));
  SolveContext ctx;
  ctx.problem = &problem;
  ctx.opt = &opt;
  std::vector<ConstraintContext> cctx;
  cctx.reserve(problem.inequality.size() + problem.equality.size());

  opt.set_min_objective(objective_trampoline, &ctx);
  if (!problem.lower.empty()) opt.set_lower_bounds(problem.lower);
  if (!problem.upper.empty()) opt.set_upper_bounds(problem.upper);
  for (const auto& c : problem.inequality) {
    cctx.push_back({&ctx, &c});
    opt.add_inequality_mconstraint(constraint_trampoline, &cctx.back(),
                                   std::vector<double>(c.size, options.constraint_tol));
  }
  for (const auto& c : problem.equality) {
    cctx.push_back({&ctx, &c});
    opt.add_equality_mconstraint(constraint_trampoline, &cctx.back(),
                                 std::vector<double>(c.size, options.constraint_tol));
  }
  opt.set_xtol_rel(options.xtol_rel);
  opt.set_ftol_rel(options.ftol_rel);
  opt.set_ftol_abs(options.ftol_abs);
  opt.set_maxeval(options.max_eval);
  opt.set_maxtime(options.max_time);

  SolverResult out;
  const auto start = std::chrono::steady_clock::now();
  ctx.start = ctx.last_call = start;
  ctx.max_time = options.max_time;
  double value = HUGE_VAL;
  int status = NLOPT_FAILURE;
  try {
    status = static_cast<int>(opt.optimize(x0, value));
  } catch (const nlopt::forced_stop&) {
    status = NLOPT_FORCED_STOP;
  } catch (const nlopt::roundoff_limited&) {
    status = NLOPT_ROUNDOFF_LIMITED;  // x0 holds NLopt's last point; often still usable
  } catch (const std::invalid_argument&) {
    if (!ctx.error) throw;
    status = NLOPT_INVALID_ARGS;
  } catch (const std::bad_alloc&) {
    if (!ctx.error) throw;
    status = NLOPT_OUT_OF_MEMORY;
  } catch (const std::runtime_error&) {  // nlopt "failure"
    if (!ctx.error) status = NLOPT_FAILURE;
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (ctx.error) std::rethrow_exception(ctx.error);
  if (ctx.deadline_stop && status == NLOPT_FORCED_STOP) status = NLOPT_MAXTIME_REACHED;
  if (status == NLOPT_ROUNDOFF_LIMITED || status == NLOPT_FAILURE) value = opt.last_optimum_value();
  out.x = std::move(x0);
  out.value = value;
  out.status = status;
  out.status_name = nlopt_status_name(status);
  out.evaluations = ctx.evaluations;
  return out;
}

}  // namespace ernest::opt
