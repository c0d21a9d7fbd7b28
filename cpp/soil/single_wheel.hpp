// Single-wheel test rig: equilibrium sinkage, drawbar pull and driving torque for a given load and
// slip, as in a terramechanics testbed where the carriage speed is fixed and the wheel spin sets
// the slip.
#pragma once

#include <Eigen/Core>

#include "ernest/soil/bekker_wong.hpp"

namespace ernest::soil {

struct RigOptions {
  double carriage_speed = 0.2;  ///< v_x [m/s]; eq 12 scales slip by (1 - exp(-eps_slip v_x^2))
  double sinkage_tolerance = 1e-9;  ///< [m]
  int max_iterations = 200;
  void validate() const;
};

struct RigResult {
  double slip = 0.0;          ///< commanded kinematic slip (driving > 0, braking < 0)
  double model_slip = 0.0;    ///< eq 12 slip seen by the model (after regularisation)
  double sinkage = 0.0;       ///< equilibrium sinkage [m]
  double drawbar_pull = 0.0;  ///< F_x [N]
  double lateral_force = 0.0; ///< F_y [N]
  double normal_force = 0.0;  ///< F_z at equilibrium [N] (= load when converged)
  double torque = 0.0;        ///< driving torque r^2 b \int tau_x [N m]
  double theta_f = 0.0, theta_m = 0.0, theta_r = 0.0;
  int iterations = 0;
  bool converged = false;     ///< false if the load exceeds what the soil carries at h = r
};

/// Contact state of a wheel on the rig at sinkage h and kinematic slip s in [-1, 1).
ContactState rig_state(double sinkage, double slip, double carriage_speed, double wheel_radius);

/// Equilibrium (F_z = load) at one slip. load in [1e-3, 1e5] N, slip in [-1, 0.99].
RigResult solve_equilibrium(const BekkerWongModel& model, double load, double slip,
                            const RigOptions& options = {});

/// Slip sweep: rows of (slip, model_slip, sinkage, drawbar_pull, normal_force, torque, converged).
Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> slip_sweep(
    const BekkerWongModel& model, double load, const Eigen::Ref<const Eigen::VectorXd>& slips,
    const RigOptions& options = {});

}  // namespace ernest::soil
