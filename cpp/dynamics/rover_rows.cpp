// ERNEST on ODE: the constraint rows of one attempt at a step (rover_step.cpp): how each guessed
// row is emitted to ODE (emit) and how its law is checked after the step (settle). Equation
// numbers refer to seed 004.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>

#include "ernest/dynamics/rover_sim_impl.hpp"

namespace ernest::dynamics {

using namespace detail;

// Drive k (wheels 0..3, yaw, roll): its guessed row, its axis and the bodies it acts between.
RoverSim::Impl::DriveRow RoverSim::Impl::drive_row(int k) const {
  if (k < 4) return {kRowsPerWheel * k + kWheelMotor, ground[k].axle, 2 + k, parent_of(k)};
  return {kYawMotor + (k - 4), k == 4 ? yaw_axis : roll_axis, kChassis, kBogie};
}

// The x and y rows at the patch are the friction rows of an ODE contact with the terrain normal n
// (fdir1 = x, then n × x = y), whose own normal row carries the normal force, bounded below by
// zero: the sparse solver (solver/sparse_lcp.cpp) solves it exactly whether it pushes or not, so it
// needs no guess of its own. A normal force guessed at zero (the wheel leaving the soil faster than
// F_z / c) keeps the row slack if shear rows need the contact.
void RoverSim::Impl::emit_ground(int i, RowModes modes, Vec3& fw, Vec3& tw) {
  const auto mode_of = [&](int row) { return modes[row]; };
  const bool soft = opt.ground == GroundType::Soil;
  struct Slot {
    Vec3 dir;
    double mu, slip, motion;
  };
  const GroundContact& g = ground[i];
  if (!g.active) return;
  const dBodyID wb = body[2 + i];
  const auto make = [&](const Vec3& normal, double motion_n, double cfm_n, const Slot* slots,
                        int n_slots, dJointFeedback* fb) {
    dContact cj;
    std::memset(&cj, 0, sizeof cj);
    for (int k = 0; k < 3; ++k) {
      cj.geom.pos[k] = g.point[k];
      cj.geom.normal[k] = normal[k];
    }
    cj.geom.depth = 0.0;  // no position correction: every row is a velocity law
    cj.surface.mode = dContactMu2 | dContactFDir1 | dContactSlip1 | dContactSlip2 |
                      dContactMotion1 | dContactMotion2 | dContactMotionN | dContactSoftERP |
                      dContactSoftCFM;
    cj.surface.soft_erp = 0.0;
    cj.surface.soft_cfm = cfm_n;
    cj.surface.motionN = motion_n;
    if (n_slots > 0) {
      for (int k = 0; k < 3; ++k) cj.fdir1[k] = slots[0].dir[k];
      cj.surface.mu = slots[0].mu;
      cj.surface.slip1 = slots[0].slip;
      cj.surface.motion1 = slots[0].motion;
    }
    if (n_slots > 1) {  // along normal x fdir1
      cj.surface.mu2 = slots[1].mu;
      cj.surface.slip2 = slots[1].slip;
      cj.surface.motion2 = slots[1].motion;
    }
    add_contact_joint(cj, wb, nullptr, fb);
  };
  if (!soft) {  // rigid ground: rover_rigid.cpp
    emit_rigid(i, modes);
    return;
  }
  // Soft soil: the explicit share of the axle torque (soil_terms), then the rows.
  tw += g.axle * g.axle_torque;
  // (c) Normal force F_n = max(0, F_z - c v_n): a damper around the soil's pressure force that
  //     never pulls; lambda = (motion - v_n) / cfm with motion = F_z / c, cfm = 1 / c. c is the
  //     soil's damper plus h dF_z/dz (eq 32's spring at the end of the step, linearised: see
  //     prepare_ground). Guessed at 0 (the wheel leaves the soil faster than F_z / c): no row.
  const double c = g.normal_damping;
  const RowState normal_mode = mode_of(kRowsPerWheel * i + kNormal);
  Slot slots[2];  // x then y: with fdir1 = x the second friction row is n × x = y
  int ns = 0;
  // (a) Shear rows: at a guessed bound, explicit forces at the patch.
  for (int k = 0; k < 2; ++k) {
    const double bound = k == 0 ? g.ax : g.ay;
    if (bound < kMinRowBound) continue;
    const Vec3& dir = k == 0 ? g.fx : g.fy;
    const RowState mode = mode_of(kRowsPerWheel * i + (k == 0 ? kShearX : kShearY));
    if (mode == RowState::AtHi || mode == RowState::AtLo) {
      add_at(fw, tw, dir * (mode == RowState::AtHi ? bound : -bound), g.arm);
      continue;
    }
    const double slip = (k == 0 ? opt.soil.eps_contact_x : opt.soil.eps_contact_y) / bound;
    slots[ns++] = Slot{dir, mode == RowState::Free ? dInfinity : bound, slip, 0.0};
  }
  if (normal_mode != RowState::AtLo || ns > 0)
    make(g.n, normal_mode != RowState::AtLo ? g.fz / c : -kSlackSpeed, 1.0 / c, slots, ns, &ground_fb[i]);
  // (b) Compaction row on the wheel centre.
  if (g.comp > 0.0) {
    const RowState mode = mode_of(kRowsPerWheel * i + kCompaction);
    if (mode == RowState::AtHi || mode == RowState::AtLo) {
      fw += g.fx * (mode == RowState::AtHi ? g.comp : -g.comp);
    } else {
      const double eps_dir = std::max(opt.soil.eps_direction, 1e-6);
      add_lmotor_joint(wb, g.fx, mode == RowState::Free ? dInfinity : g.comp, eps_dir / g.comp);
    }
  }
}

// Joints and forces of one attempt (modes: a guess, or every guessed row with its bounds).
void RoverSim::Impl::emit(RowModes modes) {
  island.clear_attempt();
  std::array<Vec3, 6> f = base_force, t = base_torque;
  const auto mode_of = [&](int row) { return modes[row]; };
  // ---- drives
  for (int k = 0; k < 6; ++k) {
    const MotorRow& m = motor[k];
    const DriveRow d = drive_row(k);
    const int row = d.row;
    const RowState mode = m.bound > 0.0 ? mode_of(row) : RowState::Bounded;
    double fmax = m.bound;
    if (mode == RowState::Free) fmax = dInfinity;
    if (mode == RowState::AtHi || mode == RowState::AtLo) {
      fmax = 0.0;
      const double lambda = mode == RowState::AtHi ? m.bound : -m.bound;
      t[d.body1] += d.axis * lambda;
      t[d.body2] -= d.axis * lambda;
    }
    // (only what changed: the joints keep their parameters between steps)
    const dJointID jm = k < 4 ? wheel_motor[k] : gimbal_motor;
    // (through the island step, which keeps a copy and may not reuse its last rows now)
    if (!(motor_set[k][0] == m.target)) {
      island.set_amotor_param(jm, k == 5 ? dParamVel2 : dParamVel, m.target);
      motor_set[k][0] = m.target;
    }
    if (!(motor_set[k][1] == fmax)) {
      island.set_amotor_param(jm, k == 5 ? dParamFMax2 : dParamFMax, fmax);
      motor_set[k][1] = fmax;
    }
  }
  // ---- ground
  for (int i = 0; i < 4; ++i) emit_ground(i, modes, f[2 + i], t[2 + i]);
  // ---- rigid obstacles (rover_rigid.cpp)
  emit_obstacles(modes);
  for (int b = 0; b < 6; ++b) {
    dBodySetForce(body[b], f[b].x(), f[b].y(), f[b].z());
    dBodySetTorque(body[b], t[b].x(), t[b].y(), t[b].z());
  }
  check_forces_before_step();
}

// After dWorldStep: the force of every guessed row and where its law puts it (next[]); returns
// whether every guess held. The laws are evaluated with the Jacobians of the start of the step
// (as ODE built them) and the velocities at its end.
bool RoverSim::Impl::settle(RowModes modes, RowStates& next) {
  bool held = true;
  const auto mode_of = [&](int row) { return modes[row]; };
  const auto outcome = [&](int row, RowState status) {
    if (!guess_holds(mode_of(row), status)) held = false;
    next[row] = status;
  };
  // ---- drives
  for (int k = 0; k < 6; ++k) {
    const MotorRow& m = motor[k];
    const DriveRow d = drive_row(k);
    const int row = d.row;
    row_force[row] = 0.0;
    if (!(m.bound > 0.0)) continue;
    const Vec3& axis = d.axis;
    const RowState mode = mode_of(row);
    if (mode == RowState::AtHi || mode == RowState::AtLo) {
      const double rate = (to_vec(dBodyGetAngularVel(body[d.body1])) -
                           to_vec(dBodyGetAngularVel(body[d.body2]))).dot(axis);
      const double demand = (m.target - rate) / kWorldCfm;  // the row's unclamped force
      row_force[row] = mode == RowState::AtHi ? m.bound : -m.bound;
      outcome(row, status_of(demand, m.bound) == mode ? mode : RowState::Free);
    } else {
      const dJointFeedback& fb = k < 4 ? wheel_motor_fb[k] : gimbal_motor_fb;
      const double lambda = to_vec(fb.t1).dot(axis);
      row_force[row] = std::clamp(lambda, -m.bound, m.bound);
      // A bounded row that ODE left at its bound is at it; a free row beyond it is not free.
      outcome(row, mode == RowState::Bounded
                       ? (std::abs(lambda) < m.bound ? RowState::Free : status_of(lambda, m.bound))
                       : status_of(lambda, m.bound));
    }
  }
  // ---- ground
  const bool soft = opt.ground == GroundType::Soil;
  for (int i = 0; i < 4; ++i) {
    const GroundContact& g = ground[i];
    for (int k : {kShearX, kShearY, kCompaction, kNormal}) row_force[kRowsPerWheel * i + k] = 0.0;
    if (!g.active) continue;
    const Vec3 v = to_vec(dBodyGetLinearVel(body[2 + i]));
    const Vec3 vp = v + to_vec(dBodyGetAngularVel(body[2 + i])).cross(g.arm);
    if (!soft) {
      if (!settle_rigid(i, modes, vp, next)) held = false;
      continue;
    }
    {  // normal force >= 0, F_z - c v_n at the patch: the contact's row, or none (guessed at 0)
      const int row = kRowsPerWheel * i + kNormal;
      const RowState mode = mode_of(row);
      if (mode != RowState::AtLo) {  // the contact's normal row, solved with its bound
        row_force[row] = to_vec(ground_fb[i].f1).dot(g.n);
        next[row] = row_force[row] > 0.0 ? RowState::Free : RowState::AtLo;
      } else {
        const double total = g.fz - g.normal_damping * vp.dot(g.n);
        row_force[row] = 0.0;
        outcome(row, total > 0.0 ? RowState::Free : RowState::AtLo);
      }
    }
    const double eps_dir = std::max(opt.soil.eps_direction, 1e-6);
    struct SoftRow {
      int kind;
      double bound, u;  // u: the row's law, lambda = (target - J v) / cfm
    };
    const SoftRow rows[3] = {
        {kShearX, g.ax >= kMinRowBound ? g.ax : 0.0, -vp.dot(g.fx) * g.ax / opt.soil.eps_contact_x},
        {kShearY, g.ay >= kMinRowBound ? g.ay : 0.0, -vp.dot(g.fy) * g.ay / opt.soil.eps_contact_y},
        {kCompaction, g.comp, -v.dot(g.fx) * g.comp / eps_dir}};
    for (const SoftRow& r : rows) {
      if (!(r.bound > 0.0)) continue;
      const int row = kRowsPerWheel * i + r.kind;
      const RowState mode = mode_of(row);
      row_force[row] = mode == RowState::AtHi ? r.bound
                       : mode == RowState::AtLo ? -r.bound
                                       : std::clamp(r.u, -r.bound, r.bound);
      outcome(row, status_of(r.u, r.bound));
    }
  }
  rows_held = held;
  if (n_obstacle_contacts > 0 && !settle_obstacles(modes)) held = false;
  return held;
}

}  // namespace ernest::dynamics
