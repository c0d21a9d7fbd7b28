// Validation of the rover's parameters (rover_parameters.hpp: seed 004 Table 1 and our
// assumptions); a motor's current and electrical power at a torque and speed (eq 40).
#include "ernest/dynamics/rover_parameters.hpp"

#include <cmath>
#include <string>

#include "ernest/common/validation.hpp"

namespace ernest::dynamics {

void MotorParameters::validate(const char* owner) const {
  const std::string o = std::string(owner);
  require_in_range(o.c_str(), "torque_constant", torque_constant, 1e-4, 10.0);
  require_in_range(o.c_str(), "resistance", resistance, 0.0, 100.0);
  require_in_range(o.c_str(), "gear_ratio", gear_ratio, 1.0, 1e4);
  require_in_range(o.c_str(), "efficiency", efficiency, 0.05, 1.0);
  require_in_range(o.c_str(), "current_limit", current_limit, 1e-3, 1e3);
  require_in_range(o.c_str(), "rotor_inertia", rotor_inertia, 0.0, 1.0);
}

MotorElectrical motor_electrical(const MotorParameters& m, double output_torque,
                                 double output_speed) {
  m.validate("MotorParameters");  // a zero torque constant would divide by zero
  const double n = m.gear_ratio, eta = m.efficiency;
  const bool motoring = output_torque * output_speed >= 0.0;
  const double rotor_torque = motoring ? output_torque / (n * eta) : output_torque * eta / n;
  MotorElectrical e;
  e.current = rotor_torque / m.torque_constant;
  const double rotor_speed = n * output_speed;
  e.power = e.current * (m.resistance * e.current + m.torque_constant * rotor_speed);  // eq 40
  return e;
}

void RoverParameters::validate() const {
  const char* o = "RoverParameters";
  require_in_range(o, "wheelbase", wheelbase, 0.1, 10.0);
  require_in_range(o, "track", track, 0.1, 10.0);
  require_in_range(o, "wheel_radius", wheel_radius, 0.02, 2.0);
  require_in_range(o, "wheel_width", wheel_width, 0.01, 2.0 * wheel_radius);
  require_in_range(o, "chassis_mass", chassis_mass, 0.1, 1e4);
  require_in_range(o, "bogie_mass", bogie_mass, 0.1, 1e4);
  require_in_range(o, "wheel_assembly_mass", wheel_assembly_mass, 0.05, 1e3);
  for (int k = 0; k < 3; ++k) {
    require_in_range(o, "chassis_com", chassis_com[k], -10.0, 10.0);
    require_in_range(o, "chassis_inertia", chassis_inertia[k], 1e-4, 1e4);
    require_in_range(o, "bogie_inertia", bogie_inertia[k], 1e-5, 1e4);
    require_in_range(o, "chassis_box", chassis_box[k], 0.01, 10.0);
    require_in_range(o, "chassis_box_centre", chassis_box_centre[k], -10.0, 10.0);
    require_in_range(o, "bogie_box", bogie_box[k], 0.01, 10.0);
  }
  // Principal inertias must satisfy the triangle inequality to be a rigid body.
  auto tri = [](const Eigen::Vector3d& i) {
    return i[0] <= i[1] + i[2] && i[1] <= i[0] + i[2] && i[2] <= i[0] + i[1];
  };
  require(tri(chassis_inertia), "RoverParameters.chassis_inertia violates the triangle inequality");
  require(tri(bogie_inertia), "RoverParameters.bogie_inertia violates the triangle inequality");
  require_in_range(o, "bogie_com_height", bogie_com_height, -2.0, 2.0);
  require_in_range(o, "wheel_spin_inertia", wheel_spin_inertia, 1e-5, 100.0);
  require_in_range(o, "wheel_transverse_inertia", wheel_transverse_inertia, 0.5 * wheel_spin_inertia,
                   100.0);
  require_in_range(o, "gimbal_height", gimbal_height, 0.0, 5.0);
  require_in_range(o, "yaw_limit", yaw_limit, 0.0, 1.5);
  require_in_range(o, "roll_limit", roll_limit, 0.0, 1.5);
  require_in_range(o, "stop_stiffness", stop_stiffness, 0.0, 1e8);
  require_in_range(o, "stop_damping", stop_damping, 0.0, 1e6);
  require_in_range(o, "yaw_brake_torque", yaw_brake_torque, 0.0, 1e5);
  require_in_range(o, "clutch_align_speed", clutch_align_speed, 1e-4, 10.0);
  require_in_range(o, "clutch_align_gain", clutch_align_gain, 1e-3, 1e3);
  require_in_range(o, "clutch_align_tolerance", clutch_align_tolerance, 1e-6, 0.5);
  wheel_motor.validate("RoverParameters.wheel_motor");
  gimbal_motor.validate("RoverParameters.gimbal_motor");
  require_in_range(o, "fts_height", fts_height, 0.0, 5.0);
  require_in_range(o, "bogie_box_height", bogie_box_height, -2.0, 5.0);
}

Eigen::Vector3d RoverParameters::wheel_centre(int i) const {
  require_in_range("RoverParameters.wheel_centre", "i", i, 0, 3);
  const double x = (i < 2 ? 0.5 : -0.5) * wheelbase;
  const double y = (i % 2 == 0 ? 0.5 : -0.5) * track;
  return {x, y, 0.0};
}

}  // namespace ernest::dynamics
