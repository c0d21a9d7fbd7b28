// ERNEST on ODE: RoverSim's public API (one thread at a time, validation, snapshot/restore, the
// state vector) over RoverSim::Impl (rover_sim_impl.hpp); the model is built in rover_sim.cpp.
#include "ernest/dynamics/rover_sim.hpp"

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "ernest/common/exclusive_use.hpp"
#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"
#include "ernest/dynamics/rover_sim_impl.hpp"

namespace ernest::dynamics {

using namespace detail;

RoverSim::RoverSim(const RoverParameters& params, const HeightMap& terrain,
                   const std::vector<BoxObstacle>& obstacles, const SimOptions& options) {
  params.validate();
  options.validate();
  for (const auto& b : obstacles) b.validate();
  impl_ = std::make_unique<Impl>(params, terrain, obstacles, options);
  impl_->build();
  reset(0.0, 0.0, 0.0);
}

RoverSim::~RoverSim() = default;

void RoverSim::reset(double x, double y, double heading, double psi, double phi, double speed) {
  const ExclusiveUse busy(impl_->in_use, "RoverSim.reset");
  require_finite("RoverSim.reset", "x", x);
  require_finite("RoverSim.reset", "y", y);
  require_finite("RoverSim.reset", "heading", heading);
  require_in_range("RoverSim.reset", "psi", psi, -impl_->p.yaw_limit, impl_->p.yaw_limit);
  require_in_range("RoverSim.reset", "phi", phi, -impl_->p.roll_limit, impl_->p.roll_limit);
  solver::init_ode_once();
  require_in_range("RoverSim.reset", "speed", speed, -5.0, 5.0);
  impl_->run_ode([&] {
    impl_->place(x, y, heading, psi, phi, speed);
    impl_->read_outputs(0.0);
  });
}

void RoverSim::set_commands(const Commands& c) {
  const ExclusiveUse busy(impl_->in_use, "RoverSim.set_commands");
  c.validate();
  impl_->cmd = c;
}

const Commands& RoverSim::commands() const { return impl_->cmd; }

void RoverSim::set_command_vector(const double* c) {
  const ExclusiveUse busy(impl_->in_use, "RoverSim.set_command_vector");
  // the flags are 0 or 1: a NaN compares != 0 and would read as true
  // messages built only on failure: this runs every step of a batch
  if (!(c[6] == 0.0 || c[6] == 1.0))
    throw std::invalid_argument("RoverSim commands: gimbal_enabled (column 6) = " +
                                std::to_string(c[6]) + " must be 0 or 1");
  if (!(c[7] == 0.0 || c[7] == 1.0))
    throw std::invalid_argument("RoverSim commands: clutch_engage (column 7) = " +
                                std::to_string(c[7]) + " must be 0 or 1");
  Commands k = impl_->cmd;
  k.wheel_mode = k.yaw_mode = k.roll_mode = ActuatorMode::Velocity;
  for (int i = 0; i < 4; ++i) k.wheel_speed[i] = c[i];
  k.yaw_rate = c[4];
  k.roll_rate = c[5];
  k.gimbal_enabled = c[6] != 0.0;
  k.clutch_engage = c[7] != 0.0;
  k.validate();
  impl_->cmd = k;
}

void RoverSim::step() {
  const ExclusiveUse busy(impl_->in_use, "RoverSim.step");
  impl_->run_ode([&] { impl_->step(); });
}

void RoverSim::step_n(int n) {
  const ExclusiveUse busy(impl_->in_use, "RoverSim.step_n");
  require(n >= 0, "RoverSim.step_n: n must be >= 0");
  impl_->run_ode([&] {
    for (int k = 0; k < n; ++k) {
      if (k > 0) poll_interrupt();  // Ctrl-C: stop between whole steps (common/interrupt.hpp)
      impl_->step();
    }
  });
}

const RoverState& RoverSim::state() const { return impl_->st; }

RoverState RoverSim::state_copy() const {
  const ExclusiveUse busy(impl_->in_use, "RoverSim.state");
  return impl_->st;
}

std::vector<std::string> RoverSim::state_vector_names() {
  std::vector<std::string> n = {"time", "x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz",
                                "wx", "wy", "wz", "roll", "pitch", "yaw", "gimbal_yaw",
                                "gimbal_roll", "gimbal_yaw_rate", "gimbal_roll_rate", "yaw_torque",
                                "roll_torque"};
  const char* w[4] = {"FL", "FR", "RL", "RR"};
  for (auto s : w) n.push_back(std::string("wheel_speed_") + s);
  for (auto s : w) n.push_back(std::string("wheel_torque_") + s);
  const char* c[6] = {"Fx", "Fy", "Fz", "Tx", "Ty", "Tz"};
  for (auto s : w)
    for (auto k : c) n.push_back(std::string("fts_") + s + "_" + k);
  for (auto s : w) n.push_back(std::string("wheel_load_") + s);
  for (auto s : w) n.push_back(std::string("sinkage_") + s);
  n.push_back("energy");
  n.push_back("clutch");
  return n;
}

void RoverSim::state_vector(double* o) const {
  const ExclusiveUse busy(impl_->in_use, "RoverSim.state_vector");
  const RoverState& s = impl_->st;
  int k = 0;
  o[k++] = s.time;
  for (int i = 0; i < 3; ++i) o[k++] = s.position[i];
  for (int i = 0; i < 4; ++i) o[k++] = s.quaternion[i];
  for (int i = 0; i < 3; ++i) o[k++] = s.linear_velocity[i];
  for (int i = 0; i < 3; ++i) o[k++] = s.angular_velocity[i];
  o[k++] = s.roll;
  o[k++] = s.pitch;
  o[k++] = s.yaw;
  o[k++] = s.gimbal_yaw;
  o[k++] = s.gimbal_roll;
  o[k++] = s.gimbal_yaw_rate;
  o[k++] = s.gimbal_roll_rate;
  o[k++] = s.yaw_torque;
  o[k++] = s.roll_torque;
  for (int i = 0; i < 4; ++i) o[k++] = s.wheel_speed[i];
  for (int i = 0; i < 4; ++i) o[k++] = s.wheel_torque[i];
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 6; ++j) o[k++] = s.fts[i][j];
  for (int i = 0; i < 4; ++i) o[k++] = s.wheel_load[i];
  for (int i = 0; i < 4; ++i) o[k++] = s.sinkage[i];
  o[k++] = s.energy;
  o[k++] = static_cast<double>(static_cast<int>(s.clutch));
}

Snapshot RoverSim::snapshot() const {
  const ExclusiveUse busy(impl_->in_use, "RoverSim.snapshot");
  Snapshot s;
  for (int b = 0; b < 6; ++b) {
    const dBodyID id = impl_->body[b];
    const dReal* x = dBodyGetPosition(id);
    const dReal* q = dBodyGetQuaternion(id);
    const dReal* v = dBodyGetLinearVel(id);
    const dReal* w = dBodyGetAngularVel(id);
    for (int k = 0; k < 3; ++k) {
      s.bodies[b].pos[k] = x[k];
      s.bodies[b].lin[k] = v[k];
      s.bodies[b].ang[k] = w[k];
    }
    for (int k = 0; k < 4; ++k) s.bodies[b].quat[k] = q[k];
  }
  s.state = impl_->st;
  s.commands = impl_->cmd;
  s.shear_x = impl_->shear_x;
  s.shear_y = impl_->shear_y;
  s.compaction = impl_->compaction;
  s.row_mode = impl_->guesser.last();
  s.row_mode_before = impl_->guesser.before();
  s.alternating = impl_->guesser.alternating();
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) s.rigid_deflection[i][k] = impl_->rigid_deflection[i][k];
  s.obstacle_mode = impl_->obstacle_mode;
  s.slip_rate = impl_->slip_rate;
  s.shear_x_past = impl_->shear_x_past;
  s.compaction_past = impl_->compaction_past;
  s.soil_steps = impl_->soil_steps;
  s.slip_offset = impl_->slip_offset;
  impl_->lcp.save(s.solver_patterns);
  s.valid = true;
  return s;
}

void RoverSim::restore(const Snapshot& s) {
  const ExclusiveUse busy(impl_->in_use, "RoverSim.restore");
  impl_->run_ode([] {});  // refuses after an ODE internal error
  require(s.valid, "RoverSim.restore: empty snapshot");
  for (const auto* modes : {&s.row_mode, &s.row_mode_before})
    for (RowState m : *modes)
      require(static_cast<int>(m) >= 0 && static_cast<int>(m) <= 3,
              "RoverSim.restore: corrupt snapshot (row_mode)");
  solver::init_ode_once();
  impl_->lcp.load(s.solver_patterns);  // first: it may throw on a corrupt snapshot
  for (int b = 0; b < 6; ++b) {
    const dBodyID id = impl_->body[b];
    const auto& sb = s.bodies[b];
    dQuaternion q = {sb.quat[0], sb.quat[1], sb.quat[2], sb.quat[3]};
    dBodySetPosition(id, sb.pos[0], sb.pos[1], sb.pos[2]);
    dBodySetQuaternion(id, q);
    dBodySetLinearVel(id, sb.lin[0], sb.lin[1], sb.lin[2]);
    dBodySetAngularVel(id, sb.ang[0], sb.ang[1], sb.ang[2]);
    dBodySetForce(id, 0, 0, 0);
    dBodySetTorque(id, 0, 0, 0);
  }
  impl_->st = s.state;
  impl_->cmd = s.commands;
  impl_->shear_x = s.shear_x;
  impl_->shear_y = s.shear_y;
  impl_->compaction = s.compaction;
  impl_->guesser.set(s.row_mode, s.row_mode_before, s.alternating);
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) impl_->rigid_deflection[i][k] = s.rigid_deflection[i][k];
  for (RowState m : s.obstacle_mode)
    require(m == RowState::Free || m == RowState::Bounded,
            "RoverSim.restore: corrupt snapshot (obstacle_mode)");
  impl_->obstacle_mode = s.obstacle_mode;
  require(std::isfinite(s.slip_rate) && s.slip_rate >= 0.0,
          "RoverSim.restore: corrupt snapshot (slip_rate)");
  impl_->slip_rate = s.slip_rate;
  for (int i = 0; i < 4; ++i) {
    require(s.soil_steps[i] >= 0 && s.soil_steps[i] <= 3,
            "RoverSim.restore: corrupt snapshot (soil_steps)");
    require(!(std::abs(s.slip_offset[i]) > 2.0) && std::isfinite(s.shear_x_past[0][i]) &&
                std::isfinite(s.shear_x_past[1][i]) && std::isfinite(s.compaction_past[0][i]) &&
                std::isfinite(s.compaction_past[1][i]),
            "RoverSim.restore: corrupt snapshot (slip warm start)");
  }
  impl_->shear_x_past = s.shear_x_past;
  impl_->compaction_past = s.compaction_past;
  impl_->soil_steps = s.soil_steps;
  impl_->slip_offset = s.slip_offset;
  // A step without obstacle contacts keeps obstacle_next as it was (settle_obstacles is not
  // called) and then takes it as obstacle_mode: between steps the two are equal, and a restored
  // (or reset) rover must have them equal too, else its first step off the rocks takes the
  // guesses of wherever the simulation last was (restored runs parted from the original).
  impl_->obstacle_next = s.obstacle_mode;
  impl_->pending_force.setZero();
  impl_->diverged = false;
  impl_->start_current = false;
}

void RoverSim::apply_chassis_force(const Eigen::Vector3d& force) {
  const ExclusiveUse busy(impl_->in_use, "RoverSim.apply_chassis_force");
  require(force.allFinite(), "RoverSim.apply_chassis_force: force must be finite");
  impl_->pending_force += force;
}

double RoverSim::kinetic_energy() const {
  const ExclusiveUse busy(impl_->in_use, "RoverSim.kinetic_energy");
  double e = 0.0;
  for (auto b : impl_->body) {
    dMass m;
    dBodyGetMass(b, &m);
    const Vec3 v = to_vec(dBodyGetLinearVel(b));
    const Mat3 r = to_mat(dBodyGetRotation(b));
    const Vec3 wl = r.transpose() * to_vec(dBodyGetAngularVel(b));
    Mat3 inertia;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) inertia(i, j) = m.I[4 * i + j];
    e += 0.5 * m.mass * v.squaredNorm() + 0.5 * wl.dot(inertia * wl);
  }
  return e;
}

double RoverSim::potential_energy() const {
  const ExclusiveUse busy(impl_->in_use, "RoverSim.potential_energy");
  double e = 0.0;
  for (auto b : impl_->body) {
    dMass m;
    dBodyGetMass(b, &m);
    e += m.mass * impl_->opt.soil.gravity * dBodyGetPosition(b)[2];
  }
  return e;
}

const SolverStats& RoverSim::solver_stats() const { return impl_->stats; }
double RoverSim::friction() const { return impl_->mu; }
const RoverParameters& RoverSim::parameters() const { return impl_->p; }
const SimOptions& RoverSim::options() const { return impl_->opt; }
const HeightMap& RoverSim::terrain() const { return impl_->hm; }

}  // namespace ernest::dynamics
