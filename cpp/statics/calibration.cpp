// Spring-constant calibration (seed 003 §5.1.3–5.1.4); see the header.
#include "ernest/statics/calibration.hpp"
#include "ernest/common/interrupt.hpp"

#include <algorithm>
#include <boost/math/tools/minima.hpp>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <unsupported/Eigen/NonLinearOptimization>
#include <unsupported/Eigen/NumericalDiff>

#include "ernest/common/validation.hpp"

namespace ernest::statics {

namespace {

void check_stances(const std::vector<CalibrationStance>& stances) {
  require(!stances.empty(), "stances must not be empty");
  for (std::size_t s = 0; s < stances.size(); ++s) {
    const CalibrationStance& st = stances[s];
    st.problem.validate();
    if (st.measured_heights.size() != st.problem.body_points.cols() ||
        st.measured_heights.size() == 0) {
      throw std::invalid_argument(
          "stances[" + std::to_string(s) + "].measured_heights has " +
          std::to_string(st.measured_heights.size()) + " entries; it needs one per body point (" +
          std::to_string(st.problem.body_points.cols()) + ", at least one)");
    }
    if (!st.measured_heights.allFinite()) {
      throw std::invalid_argument("stances[" + std::to_string(s) +
                                  "].measured_heights contains a non-finite value");
    }
  }
}

double error_unchecked(const std::vector<CalibrationStance>& stances, double k,
                       const SagOptions& options, double* max_error) {
  double sum = 0.0, worst = 0.0;
  int count = 0;
  for (const CalibrationStance& st : stances) {
    SagProblem p = st.problem;
    p.stiffness *= k;
    const SagResult r = solve_sag(p, options);
    if (r.status != SagStatus::Converged) {
      if (max_error) *max_error = std::numeric_limits<double>::infinity();
      return std::numeric_limits<double>::infinity();
    }
    const Eigen::Vector3d up = -p.gravity.normalized();
    for (Eigen::Index j = 0; j < r.body_points.cols(); ++j) {
      const double e = std::abs(up.dot(r.body_points.col(j)) - st.measured_heights(j));
      sum += e;
      worst = std::max(worst, e);
      ++count;
    }
  }
  if (max_error) *max_error = worst;
  return sum / count;
}

// Height residuals (predicted - measured) for per-foot constants exp(x_i), for Eigen's LM. A
// stance whose sag solve does not converge gets 1 m residuals: finite, and far worse than any fit.
struct PerFootFunctor {
  using Scalar = double;
  enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };
  using InputType = Eigen::VectorXd;
  using ValueType = Eigen::VectorXd;
  using JacobianType = Eigen::MatrixXd;
  const std::vector<CalibrationStance>* stances = nullptr;
  const SagOptions* options = nullptr;
  int feet = 0, measurements = 0;
  mutable int solves = 0;

  int inputs() const { return feet; }
  int values() const { return measurements; }
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& r) const {
    poll_interrupt();  // Ctrl-C in a long fit (common/interrupt.hpp): the exception ends the solve
    int row = 0;
    for (const CalibrationStance& st : *stances) {
      SagProblem p = st.problem;
      for (int i = 0; i < feet; ++i) p.stiffness.col(i) *= std::exp(x(i));
      const Eigen::Index m = st.measured_heights.size();
      ++solves;
      const SagResult res = solve_sag(p, *options);  // inputs validated before: no throw
      if (res.status != SagStatus::Converged) {
        r.segment(row, m).setOnes();
      } else {
        const Eigen::Vector3d up = -p.gravity.normalized();
        r.segment(row, m) = (up.transpose() * res.body_points).transpose() - st.measured_heights;
      }
      row += static_cast<int>(m);
    }
    return 0;
  }
};

}  // namespace

void CalibrationOptions::validate() const {
  require_positive("CalibrationOptions", "k_min", k_min);
  try {
    require_in_range("CalibrationOptions", "k_max", k_max, std::nextafter(k_min, kInf), kInf);
  } catch (const std::invalid_argument& e) {  // a coupled bound: name the other field too
    throw std::invalid_argument(std::string(e.what()) + " (k_max must exceed k_min = " +
                                std::to_string(k_min) + ")");
  }
  require_in_range("CalibrationOptions", "grid_points", grid_points, 3, 1e6);
  require_in_range("CalibrationOptions", "brent_bits", brent_bits, 8, 52);
  sag.validate();
}

double mean_height_error(const std::vector<CalibrationStance>& stances, double k,
                         const SagOptions& options, double* max_error) {
  check_stances(stances);
  require_positive("mean_height_error", "k", k);
  return error_unchecked(stances, k, options, max_error);
}

CalibrationResult calibrate_spring_constant(const std::vector<CalibrationStance>& stances,
                                            const CalibrationOptions& options) {
  options.validate();
  check_stances(stances);
  CalibrationResult res;
  const int g = options.grid_points;
  const double lo = std::log(options.k_min), hi = std::log(options.k_max);
  res.grid_k.resize(g);
  res.grid_error.resize(g);
  int best = 0;
  for (int i = 0; i < g; ++i) {  // §5.1.3: evaluate every constant, keep the lowest mean error
    res.grid_k(i) = std::exp(lo + (hi - lo) * i / (g - 1));
    res.grid_error(i) = error_unchecked(stances, res.grid_k(i), options.sag, nullptr);
    if (res.grid_error(i) < res.grid_error(best)) best = i;
  }
  res.sag_solves = g * static_cast<int>(stances.size());
  res.k_grid = res.k = res.grid_k(best);
  res.error_grid = res.mean_error = res.grid_error(best);
  if (options.refine && std::isfinite(res.error_grid)) {
    // Brent on log k between the grid neighbours of the best point.
    const double a = std::log(res.grid_k(std::max(best - 1, 0)));
    const double b = std::log(res.grid_k(std::min(best + 1, g - 1)));
    int evals = 0;
    const auto [x, fx] = boost::math::tools::brent_find_minima(
        [&](double logk) {
          ++evals;
          return error_unchecked(stances, std::exp(logk), options.sag, nullptr);
        },
        a, b, options.brent_bits);
    res.sag_solves += evals * static_cast<int>(stances.size());
    if (fx <= res.error_grid) {
      res.k = std::exp(x);
      res.mean_error = fx;
    }
  }
  error_unchecked(stances, res.k, options.sag, &res.max_error);
  res.sag_solves += static_cast<int>(stances.size());
  return res;
}

PerFootCalibrationResult calibrate_per_foot_constants(
    const std::vector<CalibrationStance>& stances, double k_initial, const SagOptions& options) {
  check_stances(stances);
  require_positive("calibrate_per_foot_constants", "k_initial", k_initial);
  options.validate();
  const int n = static_cast<int>(stances.front().problem.feet.cols());
  int measurements = 0;
  for (std::size_t s = 0; s < stances.size(); ++s) {
    if (stances[s].problem.feet.cols() != n) {
      throw std::invalid_argument("stances[" + std::to_string(s) + "].problem.feet has " +
                                  std::to_string(stances[s].problem.feet.cols()) +
                                  " feet; every stance needs " + std::to_string(n));
    }
    measurements += static_cast<int>(stances[s].measured_heights.size());
  }
  require(measurements >= n, "per-foot calibration needs at least as many measured heights (" +
                                 std::to_string(measurements) + ") as feet (" +
                                 std::to_string(n) + ")");
  PerFootFunctor fn;
  fn.stances = &stances;
  fn.options = &options;
  fn.feet = n;
  fn.measurements = measurements;
  Eigen::NumericalDiff<PerFootFunctor> diff(fn);
  Eigen::LevenbergMarquardt<Eigen::NumericalDiff<PerFootFunctor>> lm(diff);
  lm.parameters.ftol = lm.parameters.xtol = 1e-12;
  lm.parameters.maxfev = 100 * (n + 1);
  Eigen::VectorXd x = Eigen::VectorXd::Constant(n, std::log(k_initial));
  PerFootCalibrationResult res;
  res.lm_status = static_cast<int>(lm.minimize(x));
  res.k = x.array().exp();
  Eigen::VectorXd r(measurements);
  diff(x, r);
  res.mean_error = r.cwiseAbs().mean();
  res.max_error = r.cwiseAbs().maxCoeff();
  res.sag_solves = diff.solves;  // NumericalDiff holds its own copy of the functor
  return res;
}

}  // namespace ernest::statics
