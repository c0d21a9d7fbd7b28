// Spring-constant calibration (seed 003 §5.1.3–5.1.4); see the header.
#include "ernest/statics/calibration.hpp"

#include <algorithm>
#include <boost/math/tools/minima.hpp>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

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

}  // namespace

void CalibrationOptions::validate() const {
  require_positive("CalibrationOptions", "k_min", k_min);
  require_in_range("CalibrationOptions", "k_max", k_max, std::nextafter(k_min, kInf), kInf);
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

}  // namespace ernest::statics
