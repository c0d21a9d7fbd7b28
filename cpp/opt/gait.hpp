// Gaits as maps from phase to joint space (seed 000 eq 1) and their workspace trajectories
// G(t) (eqs 6–7).
#pragma once

#include <Eigen/Core>
#include <string>

#include "ernest/opt/asterix_model.hpp"

namespace ernest::opt {

/// A periodic gait g: P -> Q (eq 1), one sinusoid per joint:
///   q_j(t) = offset_j + amplitude_j sin(2 pi t / period + phase_j),
/// with the phase measured in seconds (t), as the paper writes g(t).
class Gait {
 public:
  Gait(std::string name, double period, Eigen::VectorXd offset, Eigen::VectorXd amplitude,
       Eigen::VectorXd phase);

  const std::string& name() const { return name_; }
  double period() const { return period_; }
  int joints() const { return static_cast<int>(offset_.size()); }
  const Eigen::VectorXd& offset() const { return offset_; }
  const Eigen::VectorXd& amplitude() const { return amplitude_; }
  const Eigen::VectorXd& phase() const { return phase_; }

  /// Joint j's position, velocity and acceleration at phase t (no allocation).
  void evaluate(int j, double t, double& q, double& dq, double& ddq) const;
  Eigen::VectorXd position(double t) const;
  Eigen::VectorXd velocity(double t) const;
  Eigen::VectorXd acceleration(double t) const;
  /// Throws std::invalid_argument if the gait leaves the limits.
  void check_limits(const Eigen::VectorXd& position_limit, const Eigen::VectorXd& velocity_limit) const;

 private:
  std::string name_;
  double period_;
  Eigen::VectorXd offset_, amplitude_, phase_;
};

/// Phase origin (ours, from seed 000 §6): every gait starts at phase 0 with the steering at its
/// positive extreme (a cosine). The paper's Naive strategy "always resets to the initial position
/// of g2: g2(0), meaning it biases towards that side", so g2(0) is to one side, not the centre.
/// (With a sine origin the Naive reset straightened the rover: measured over the §5 protocol it
/// then had the LOWEST heading change and a duration below Linear/Spline's, the reverse of §6.)
///
/// Squirming (§5, Fig. 5): the steering joint oscillates between (92% of) its limits, roll fixed
/// at 0. Period 8 s (ours): peak steering rate 0.43 rad/s with the default limits.
Gait squirming(const AsterixParameters& p = {});
/// Wheel-walking (§5, Fig. 6): steering and rear roll both oscillate, the roll a quarter period
/// ahead so the load shifts to two wheels while one lifts. Amplitudes 0.35 rad and 0.30 rad,
/// period 10 s (ours).
Gait wheel_walking(const AsterixParameters& p = {});

/// Workspace trajectory of a gait (eqs 6–7): the pose reached at phase t_end when executing the
/// gait from phase t_start at pose `start` (integrated with AsterixKinematics, steering = joint 0).
Pose2 gait_pose(const AsterixKinematics& kin, const Gait& gait, double t_start, double t_end,
                const Pose2& start = {}, const IntegrationOptions& options = {});

}  // namespace ernest::opt
