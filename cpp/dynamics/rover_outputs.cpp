// ERNEST on ODE: what a step reports (sensors, drive torques, electrical power of eq 40) and the
// checks that turn a blown-up step into SimulationDiverged.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>

#include "ernest/dynamics/rover_sim_impl.hpp"

namespace ernest::dynamics {

using namespace detail;

void RoverSim::Impl::read_outputs(double dt) {
  if (!quaternions_fixed)
    for (auto b : body) solver::canonicalise_quaternion(b);
  quaternions_fixed = false;  // (until the next own step)
  st.time += dt;
  const Mat3 rc = rot(kChassis);
  const Vec3 origin = pos(kChassis) - rc * p.chassis_com;
  st.position = origin;
  const dReal* q = dBodyGetQuaternion(body[kChassis]);
  st.quaternion = Eigen::Vector4d(q[0], q[1], q[2], q[3]);
  const Vec3 w = to_vec(dBodyGetAngularVel(body[kChassis]));
  dVector3 vo;
  dBodyGetPointVel(body[kChassis], origin.x(), origin.y(), origin.z(), vo);
  st.linear_velocity = to_vec(vo);
  st.angular_velocity = w;
  st.body_linear_velocity = rc.transpose() * st.linear_velocity;
  st.body_angular_velocity = rc.transpose() * w;
  st.yaw = std::atan2(rc(1, 0), rc(0, 0));
  st.pitch = std::asin(std::clamp(-rc(2, 0), -1.0, 1.0));
  st.roll = std::atan2(rc(2, 1), rc(2, 2));

  double psi, phi, psid, phid;
  Vec3 ez, ea;
  gimbal_angles(psi, phi, psid, phid, ez, ea);
  // What the next step starts from (the bodies do not change before it unless restored).
  start_psi = psi;
  start_phi = phi;
  yaw_axis = ez;
  roll_axis = ea;
  start_current = true;
  st.gimbal_yaw = psi;
  st.gimbal_roll = phi;
  st.gimbal_yaw_rate = psid;
  st.gimbal_roll_rate = phid;
  // Gimbal torques on the bogie: the universal joint's feedback (constraint and stops) moved to
  // the joint centre and projected on each axis (the cross-axis constraint torque is orthogonal
  // to both), plus the drives: a drive row pushes the bogie with -lambda, a set-point with +t.
  const Vec3 gpt = pos(kChassis) + rc * (p.gimbal_point() - p.chassis_com);
  const Vec3 f2 = to_vec(gimbal_fb.f2), t2 = to_vec(gimbal_fb.t2);
  const Vec3 tg = t2 + (pos(kBogie) - gpt).cross(f2);
  st.yaw_torque = tg.dot(ez) - row_force[kYawMotor] + explicit_motor_torque[4];
  st.roll_torque = tg.dot(ea) - row_force[kRollMotor] + explicit_motor_torque[5];

  for (int i = 0; i < 4; ++i) {
    const int par = parent_of(i);
    const Vec3 a = axle_world(i);
    const Vec3 c = pos(2 + i);
    st.wheel_position[i] = c;
    st.wheel_speed[i] = (to_vec(dBodyGetAngularVel(body[2 + i])) -
                         to_vec(dBodyGetAngularVel(body[par]))).dot(a);
    const Vec3 f1 = to_vec(hinge_fb[i].f1), t1 = to_vec(hinge_fb[i].t1);
    const double drive = row_force[kRowsPerWheel * i + kWheelMotor] + explicit_motor_torque[i];
    st.wheel_torque[i] = drive;  // the hinge's own rows are orthogonal to the axle
    // FTS: wrench of the assembly on its mount = minus what the mount applies to the assembly
    // (hinge constraint + drive reaction), moved to the sensor point, in the mount's frame.
    const Mat3 rp = rot(par);
    const Vec3 force = -f1;
    const Vec3 torque_c = -(t1 + drive * a);
    const Vec3 s = c + rp.col(2) * p.fts_height;
    const Vec3 torque_s = torque_c + (c - s).cross(force);
    st.fts[i].head<3>() = rp.transpose() * force;
    st.fts[i].tail<3>() = rp.transpose() * torque_s;
    // Ground normal load and the implicit levels for the next step's explicit terms.
    const GroundContact& g = ground[i];
    st.wheel_load[i] = dt > 0.0 && g.active ? row_force[kRowsPerWheel * i + kNormal] : 0.0;
    if (dt > 0.0) soil_levels(i);
    else shear_x[i] = shear_y[i] = compaction[i] = 0.0;
  }
  // Electrical power (eq 40) and energy (positive power only: the drives do not regenerate).
  for (int i = 0; i < 4; ++i) {
    const MotorElectrical e = motor_electrical(p.wheel_motor, st.wheel_torque[i], st.wheel_speed[i]);
    st.motor_current[i] = e.current;
    st.motor_power[i] = e.power;
  }
  MotorElectrical ey{}, er{};
  if (cmd.gimbal_enabled) {  // AGS off: power-on-to-disengage brakes hold at zero power
    ey = motor_electrical(p.gimbal_motor, st.yaw_torque, psid);
    if (st.clutch == ClutchState::Engaged) er = motor_electrical(p.gimbal_motor, st.roll_torque, phid);
  }
  st.motor_current[4] = ey.current;
  st.motor_power[4] = ey.power;
  st.motor_current[5] = er.current;
  st.motor_power[5] = er.power;
  for (double pw : st.motor_power) st.energy += std::max(pw, 0.0) * dt;
}

void RoverSim::Impl::check_forces_before_step() {
  constexpr double kMaxForce = 1e8;  // [N] and [N m]; 1e6 x the rover's weight
  for (int b = 0; b < 6; ++b) {
    const Vec3 f = to_vec(dBodyGetForce(body[b])), t = to_vec(dBodyGetTorque(body[b]));
    // (squared norms: a NaN fails the comparison, an infinity exceeds the bound)
    if (f.squaredNorm() <= kMaxForce * kMaxForce && t.squaredNorm() <= kMaxForce * kMaxForce)
      continue;
    diverged = true;
    for (auto id : body) {
      dBodySetForce(id, 0, 0, 0);
      dBodySetTorque(id, 0, 0, 0);
    }
    dJointGroupEmpty(contacts);
    std::ostringstream os;
    os << "SimulationDiverged at t = " << st.time << " s: applied force " << f.norm()
       << " N / torque " << t.norm() << " N m on the " << kBodyNames[b] << " is non-finite or above "
       << kMaxForce << "; restore a snapshot or reset";
    throw SimulationDiverged(os.str());
  }
}

void RoverSim::Impl::check_divergence() {
  for (int b = 0; b < 6; ++b) {
    const Vec3 x = pos(b), v = to_vec(dBodyGetLinearVel(body[b])),
               w = to_vec(dBodyGetAngularVel(body[b]));
    const bool finite = x.allFinite() && v.allFinite() && w.allFinite();
    const bool fast = finite && v.squaredNorm() > opt.max_speed * opt.max_speed;
    const bool spinning = finite && w.squaredNorm() > opt.max_angular_speed * opt.max_angular_speed;
    const bool far = finite && x.squaredNorm() > 1e12;
    if (finite && !fast && !spinning && !far) continue;  // (the message only when it is thrown)
    const std::string what =
        !finite ? "non-finite state"
        : fast  ? "speed " + std::to_string(v.norm()) + " m/s > max_speed " +
                     std::to_string(opt.max_speed)
        : spinning ? "angular speed " + std::to_string(w.norm()) + " rad/s > max_angular_speed " +
                         std::to_string(opt.max_angular_speed)
                   : "position beyond 1e6 m";
    diverged = true;
    std::ostringstream os;
    os << "SimulationDiverged at t = " << st.time << " s: " << kBodyNames[b] << " " << what
       << " (dt = " << opt.dt << " s); restore a snapshot or reset";
    throw SimulationDiverged(os.str());
  }
}

}  // namespace ernest::dynamics
