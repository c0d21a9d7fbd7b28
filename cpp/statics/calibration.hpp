// Spring-constant calibration of the sag model (seed 003 §5.1.2–5.1.4): given the measured
// heights of chosen rigid-body points (leg attachment corners, ...) in several stances, find the
// spring constant that minimises the mean absolute height error. As the paper does, by
// exhaustive search over a grid of constants; then refined by Brent's method
// (boost::math::tools::brent_find_minima) inside the bracket around the best grid point.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "ernest/statics/sag.hpp"

namespace ernest::statics {

/// One measured stance. `problem.stiffness` is read as *relative* stiffness: the model uses
/// k * problem.stiffness, so all ones calibrates one constant for every spring, and other values
/// keep a known anisotropy (k_xx/k_zz) or per-tyre differences (§5.1.4) while k is fitted.
struct CalibrationStance {
  SagProblem problem;
  /// Measured height (along -gravity) of each column of problem.body_points after sag [m].
  Eigen::VectorXd measured_heights;
};

struct CalibrationOptions {
  double k_min = 1e3;    ///< lower end of the search [N/m] (> 0)
  double k_max = 1e7;    ///< upper end [N/m] (> k_min)
  int grid_points = 61;  ///< exhaustive search, log-spaced between k_min and k_max (>= 3)
  bool refine = true;    ///< run Brent's method around the best grid point
  int brent_bits = 40;   ///< precision requested from brent_find_minima, [8, 52]
  SagOptions sag;
  void validate() const;
};

struct CalibrationResult {
  double k_grid = 0.0;       ///< best grid constant (the paper's exhaustive search) [N/m]
  double error_grid = 0.0;   ///< its mean absolute height error [m]
  double k = 0.0;            ///< refined constant (= k_grid without refinement) [N/m]
  double mean_error = 0.0;   ///< its mean absolute height error [m]
  double max_error = 0.0;    ///< its largest absolute height error [m]
  Eigen::VectorXd grid_k;      ///< the constants searched
  Eigen::VectorXd grid_error;  ///< their mean errors (+inf where a stance did not converge)
  int sag_solves = 0;
};

/// Per-foot constants (§5.1.4: unequal tyre pressures): k_i multiplies column i of every stance's
/// relative stiffness.
struct PerFootCalibrationResult {
  Eigen::VectorXd k;        ///< one constant per foot [N/m]
  double mean_error = 0.0;  ///< mean absolute height error [m]
  double max_error = 0.0;   ///< largest absolute height error [m]
  int sag_solves = 0;
  int lm_status = 0;        ///< Eigen LevenbergMarquardt status (1–4: converged)
};

/// Mean absolute height error of the stances with spring constant k (+inf if any stance's sag
/// solve does not converge). Validates the stances (std::invalid_argument naming the field).
double mean_height_error(const std::vector<CalibrationStance>& stances, double k,
                         const SagOptions& options = {}, double* max_error = nullptr);

/// The calibration. Throws std::invalid_argument for an empty set, mismatched sizes or
/// invalid options.
CalibrationResult calibrate_spring_constant(const std::vector<CalibrationStance>& stances,
                                            const CalibrationOptions& options = {});

/// Per-foot constants by least squares on the height errors: Eigen's LevenbergMarquardt with a
/// forward-difference Jacobian (Eigen::NumericalDiff) over log k_i, started from `k_initial`
/// (e.g. the single constant of calibrate_spring_constant). Every stance must have the same
/// number of feet, and there must be at least as many measured heights as feet.
PerFootCalibrationResult calibrate_per_foot_constants(
    const std::vector<CalibrationStance>& stances, double k_initial,
    const SagOptions& options = {});

}  // namespace ernest::statics
