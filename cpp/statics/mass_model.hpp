// ERNEST's two-body mass model (seed 004 §3.2, eq 11): the bogie assembly (bogie + front wheel
// assemblies) and the chassis (the rest, rear wheel assemblies included), joined by the Active
// Gimbal Suspension. With a known torque at the roll joint (zero when the clutch is open, as in
// §3.2) the rover is statically determinate: four vertical wheel loads from four equations.
// Identification of (m_c, m_b, x_c, y_c, z_c, z_b) by Levenberg–Marquardt (Eigen's unsupported
// module) with parameter uncertainty from the Jacobian at the optimum.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "ernest/dynamics/rover_parameters.hpp"

namespace ernest::statics {

/// The six parameters of eq 11, in the rover frame of dynamics::RoverParameters (x forward, y left,
/// z up, origin at the centre of the four wheel centres at psi = phi = 0, at axle height).
struct MassModel {
  double chassis_mass = 57.0;  ///< m_c [kg]: chassis, mast, avionics, rear wheel assemblies
  double bogie_mass = 18.0;    ///< m_b [kg]: bogie, bogie frame, front wheel assemblies
  /// (x_c, y_c, z_c) [m]: chassis CoM in the rover frame.
  Eigen::Vector3d chassis_com{-0.15, 0.0, 0.30};
  /// z_b [m]: bogie CoM height above the axles; the CoM lies in the bogie's median and transverse
  /// planes (§3.2), i.e. on the line through the gimbal point along the bogie's z axis.
  double bogie_com_height = 0.07;

  void validate() const;  ///< masses > 0, positions finite and within 10 m
  /// As a vector (m_c, m_b, x_c, y_c, z_c, z_b), the order of every 6-vector below.
  Eigen::Matrix<double, 6, 1> vector() const;
  static MassModel from_vector(const Eigen::Ref<const Eigen::Matrix<double, 6, 1>>& v);
  /// The simulator's own model: RoverParameters' bodies grouped as §3.2 groups them (each wheel
  /// assembly's CoM at its wheel centre, as cpp/dynamics builds it).
  static MassModel from_parameters(const dynamics::RoverParameters& p);
};

/// Names of the six parameters, in MassModel::vector() order.
const std::array<const char*, 6>& mass_model_parameter_names();

/// The fixed geometry the model uses (not identified): Table 1 and the gimbal of RoverParameters.
struct RoverGeometry {
  double wheelbase = 0.86;     ///< [m]
  double track = 0.80;         ///< [m]
  double wheel_radius = 0.17;  ///< [m]
  double tube_radius = 0.065;  ///< torus tube radius of the tyre, b/2 [m] (contact point, §3.3)
  double gimbal_height = 0.25; ///< yaw/roll axes' intersection above the front-axle centre [m]
  double gravity = 9.81;       ///< [m/s^2]

  void validate() const;
  static RoverGeometry from_parameters(const dynamics::RoverParameters& p, double gravity = 9.81);
};

/// One static configuration, and the loads measured in it (for identification).
struct LoadPose {
  /// Chassis orientation in the world (w, x, y, z), z up; its heading does not matter.
  Eigen::Vector4d chassis_quaternion{1.0, 0.0, 0.0, 0.0};
  double psi = 0.0;  ///< gimbal yaw [rad]
  double phi = 0.0;  ///< gimbal roll [rad]
  /// Torque the roll actuator applies to the bogie about the roll axis [N m]; 0 with the clutch
  /// open (§3.2's assumption that makes the system determinate).
  double roll_torque = 0.0;
  /// Ground normal under the wheels (world, need not be unit): locates each wheel's contact point,
  /// the torus tyre's deepest point along -n (§3.3). Vertical on flat ground and blocks.
  Eigen::Vector3d ground_normal{0.0, 0.0, 1.0};
  /// Measured vertical wheel–ground forces f_z,i [N], FL, FR, RL, RR (only used by the fit).
  Eigen::Vector4d loads = Eigen::Vector4d::Zero();
  /// Horizontal (world x, y) components of each wheel's ground force [N], column per wheel, when
  /// measured (a 6-axis FTS gives them). Zero: eq 11 as printed, whose model has vertical forces
  /// only. Known, they enter the moment balances and the statics stay exact when the tyres carry
  /// friction (on a slope, or scrubbed sideways while the bogie rolled into place).
  Eigen::Matrix<double, 2, 4> horizontal_forces = Eigen::Matrix<double, 2, 4>::Zero();

  /// Finite, non-zero quaternion and normal; `index` (poses[index]) names the pose in messages.
  void validate(std::optional<int> index = std::nullopt) const;
};

/// The statics of one pose as a linear system A f = b + t tau in the four vertical loads f and the
/// roll torque tau: rows are vertical force balance, moments about the world x and y axes (through
/// the rover origin), and the moment about the roll axis on the bogie assembly.
struct LoadEquations {
  Eigen::Matrix4d A;
  Eigen::Vector4d b;  ///< gravity terms, and the horizontal forces' moments when given
  Eigen::Vector4d t;  ///< coefficient of the roll torque
  std::array<Eigen::Vector3d, 4> contact;  ///< contact points relative to the rover origin (world axes)
};
LoadEquations load_equations(const MassModel& model, const RoverGeometry& geometry,
                             const LoadPose& pose);

/// Vertical wheel loads predicted by the mass model (eq 11's f̂_z,i) for the pose's roll torque.
Eigen::Vector4d predict_loads(const MassModel& model, const RoverGeometry& geometry,
                              const LoadPose& pose);

struct MassFitOptions {
  int max_evaluations = 2000;  ///< LM function evaluations
  double tolerance = 1e-12;    ///< relative tolerance on the parameters and the sum of squares
  /// Parameters held at their initial value (MassModel::vector() order), e.g. a bogie mass weighed
  /// on its own. Needed with ERNEST's geometry: the gimbal point lies on the bogie's CoM line
  /// (yaw and roll axes intersect above the front-axle centre), so moving mass between the bogie
  /// and the chassis at that point changes no load: wheel loads identify only five of the six
  /// parameters (tested; MassFitResult::identifiable says which).
  std::array<bool, 6> fixed{};
  void validate() const;
};

struct MassFitResult {
  MassModel model;
  /// 1-sigma errors; 0 for a fixed parameter, +inf for one the poses cannot identify.
  Eigen::Matrix<double, 6, 1> std_error;
  /// sigma^2 (J^T J)^+ (pseudo-inverse over the free parameters; NaN rows for the unidentifiable).
  Eigen::Matrix<double, 6, 6> covariance;
  /// false for a free parameter that moves along a direction of (numerically) zero Jacobian.
  std::array<bool, 6> identifiable{};
  double r_squared = 0.0;   ///< 1 - SSE / sum (f - mean f)^2 over all loads (paper: 0.96)
  double rmse = 0.0;        ///< sqrt(SSE / n) [N]
  double residual_sigma = 0.0;  ///< sqrt(SSE / (n - p)) [N], the noise level the covariance uses
  int evaluations = 0;
  int rank = 0;             ///< numerical rank of the free parameters' Jacobian
  bool converged = false;
  std::string status;       ///< Eigen's LM status
};

/// Fit eq 11 by Levenberg–Marquardt (Eigen::LevenbergMarquardt, analytic Jacobian) from an
/// initial guess. Needs at least 2 poses; throws std::invalid_argument on bad input.
MassFitResult fit_mass_model(const std::vector<LoadPose>& poses, const RoverGeometry& geometry,
                             const MassModel& initial = {}, const MassFitOptions& options = {});

}  // namespace ernest::statics
