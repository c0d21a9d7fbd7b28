// ERNEST on ODE: one physics step. Equation numbers refer to seed 004.
//
// Why the step is organised as it is (benchmarks/RESULTS.md, "dynamics"): dWorldStep solves the
// constraint forces as a mixed LCP by Dantzig's pivoting method. Unbounded rows (the joints) are
// factorised together up front; every bounded row (drive torque limits, the soil's shear and
// compaction caps, contact normals) is added by a pivot costing O(m^2), and a row that ends at a
// bound costs several. Slipping wheels saturate the soil's caps, so pivoting took 70 % of a step
// on soft soil. The bounded rows are therefore guessed from the previous step: a row inside its
// bounds is emitted unbounded, a row at a bound as the explicit force at that bound, and after
// the step every guess is checked against its row's law. Checked guesses are the LCP solution (it
// is unique: J M^-1 J^T + CFM is positive definite); a wrong guess is retried (up to three
// guesses), then the step is redone with bounded rows and ODE pivots as before.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>

#include "ernest/dynamics/rover_sim_impl.hpp"

namespace ernest::dynamics {

using namespace detail;

namespace {

constexpr int kMaxGuesses = 3;
// Below 1 mN a soil row is dropped: a CFM of eps / F would overflow the LCP as F -> 0.
constexpr double kMinRowBound = 1e-3;
constexpr std::int8_t kBounded = 3;  // emit the row with its bounds and let ODE pivot
constexpr double kSlackSpeed = 100.0;  // [m/s] a normal row aiming at -100 m/s never engages
constexpr double kStickMargin = 0.8;   // rigid friction above 0.8 mu F_n: solved bounded next step

inline double clamp_unit(double v) { return std::min(1.0, std::max(-1.0, v)); }

// Where a soft row's law lambda = u puts it for bounds +-bound.
inline std::int8_t status_of(double u, double bound) {
  return u >= bound ? kAtHi : (u <= -bound ? kAtLo : kFree);
}

void add_at(Vec3& f, Vec3& t, const Vec3& force, const Vec3& arm) {
  f += force;
  t += arm.cross(force);
}

}  // namespace

void RoverSim::Impl::gimbal_angles(double& psi, double& phi, double& psid, double& phid, Vec3& ez,
                                   Vec3& ea) const {
  // R_c^T R_b = R_z(psi) R_x(phi): yaw about the chassis z, then roll about the bogie x.
  const Mat3 rc = rot(kChassis), rb = rot(kBogie);
  const Mat3 rel = rc.transpose() * rb;
  psi = std::atan2(rel(1, 0), rel(0, 0));
  phi = std::atan2(rel(2, 1), rel(2, 2));
  ez = rc.col(2);
  ea = rb.col(0);
  const Vec3 wrel = to_vec(dBodyGetAngularVel(body[kBogie])) -
                    to_vec(dBodyGetAngularVel(body[kChassis]));
  psid = wrel.dot(ez);  // ez is orthogonal to ea, so the relative rate splits exactly
  phid = wrel.dot(ea);
}

// Drive rows (velocity servo up to the current-limited torque, eq 40's motor), the roll clutch
// and the joint stops. A drive row acts on (w_1 - w_2) . axis with body 1 the wheel (wheels) or
// the chassis (gimbal), hence the gimbal targets' minus sign.
void RoverSim::Impl::prepare_actuators(double psi, double phi) {
  const double dt = opt.dt;
  const double wheel_max = p.wheel_motor.max_output_torque();
  explicit_motor_torque.fill(0.0);
  for (int i = 0; i < 4; ++i) {
    motor[i] = MotorRow{};
    if (cmd.wheel_mode == ActuatorMode::Velocity) {
      motor[i] = MotorRow{cmd.wheel_speed[i], wheel_max};
    } else if (cmd.wheel_mode == ActuatorMode::Torque) {
      const double t = std::clamp(cmd.wheel_torque[i], -wheel_max, wheel_max);
      explicit_motor_torque[i] = t;
      const Vec3 a = axle_world(i) * t;
      base_torque[2 + i] += a;
      base_torque[parent_of(i)] -= a;
    }
  }
  const double gimbal_max = p.gimbal_motor.max_output_torque();
  // Torque-mode gimbal set-points act on the bogie (+) against the chassis (-).
  const auto pair_torque = [&](int k, const Vec3& axis, double t) {
    explicit_motor_torque[k] = t;
    base_torque[kBogie] += axis * t;
    base_torque[kChassis] -= axis * t;
  };
  // ---- yaw: drive, or the brake when the AGS is off
  motor[4] = MotorRow{};
  if (!cmd.gimbal_enabled) {
    motor[4] = MotorRow{0.0, p.yaw_brake_torque};
  } else if (cmd.yaw_mode == ActuatorMode::Velocity) {
    motor[4] = MotorRow{-cmd.yaw_rate, gimbal_max};
  } else if (cmd.yaw_mode == ActuatorMode::Torque) {
    pair_torque(4, yaw_axis, std::clamp(cmd.yaw_torque, -gimbal_max, gimbal_max));
  }
  // ---- roll clutch (§2.2): align the bogie frame with the bogie at bounded speed, then engage.
  if (!cmd.clutch_engage) {
    st.clutch = ClutchState::Disengaged;
  } else if (st.clutch == ClutchState::Disengaged) {
    st.clutch = ClutchState::Aligning;
  }
  if (st.clutch == ClutchState::Aligning) {
    const double err = phi - st.bogie_frame_angle;
    const double v = std::clamp(p.clutch_align_gain * err, -p.clutch_align_speed,
                                p.clutch_align_speed);
    st.bogie_frame_angle += v * dt;
    if (std::abs(phi - st.bogie_frame_angle) <= p.clutch_align_tolerance) {
      st.clutch = ClutchState::Engaged;
    }
  } else if (st.clutch == ClutchState::Disengaged && cmd.gimbal_enabled) {
    // The unloaded frame follows the roll command (it can move with the clutch open).
    st.bogie_frame_angle = std::clamp(st.bogie_frame_angle + cmd.roll_rate * dt, -p.roll_limit,
                                      p.roll_limit);
  }
  motor[5] = MotorRow{};  // pins out: the bogie rolls freely on its bearing
  if (st.clutch == ClutchState::Engaged) {
    st.bogie_frame_angle = phi;
    if (!cmd.gimbal_enabled) {  // roll actuator braked, pins in: bogie held
      motor[5] = MotorRow{0.0, p.yaw_brake_torque};
    } else if (cmd.roll_mode == ActuatorMode::Velocity) {
      motor[5] = MotorRow{-cmd.roll_rate, gimbal_max};
    } else if (cmd.roll_mode == ActuatorMode::Torque) {
      pair_torque(5, roll_axis, std::clamp(cmd.roll_torque, -gimbal_max, gimbal_max));
    }
  }
  // ---- joint stops as stiff spring–dampers (§3.1): ODE's stops with the spring k and damper c
  // mapped to ERP = h k / (h k + c), CFM = 1 / (h k + c) so that they stay stable at large steps.
  // ODE engages a stop when the angle at the start of the step is beyond it, which it checks by
  // computing both angles every step; so a stop is only set while its angle is within 1e-6 rad
  // of it (our angles and ODE's agree far closer), which gives the same rows and spares that.
  const double kh = dt * p.stop_stiffness + p.stop_damping;
  for (int ax = 0; ax < 2; ++ax) {
    const double lim = ax == 0 ? p.yaw_limit : p.roll_limit;
    const bool near = std::abs(ax == 0 ? psi : phi) >= lim - 1e-6;
    if (near == stop_set[ax]) continue;
    stop_set[ax] = near;
    dJointSetUniversalParam(gimbal, ax == 0 ? dParamLoStop : dParamLoStop2,
                            near ? -lim : -dInfinity);
    dJointSetUniversalParam(gimbal, ax == 0 ? dParamHiStop : dParamHiStop2,
                            near ? lim : dInfinity);
    dJointSetUniversalParam(gimbal, ax == 0 ? dParamStopERP : dParamStopERP2,
                            dt * p.stop_stiffness / kh);
    dJointSetUniversalParam(gimbal, ax == 0 ? dParamStopCFM : dParamStopCFM2, 1.0 / kh);
  }
}

void RoverSim::Impl::prepare_ground() {
  const bool soft = opt.ground == GroundType::Soil;
  for (int i = 0; i < 4; ++i) {
    GroundContact& g = ground[i];
    g = GroundContact{};
    st.sinkage[i] = 0.0;
    st.slip[i] = 0.0;
    st.contact_vx[i] = st.contact_vy[i] = 0.0;
    const dBodyID wb = body[2 + i];
    const Vec3 c = pos(2 + i), a = axle_world(i);
    const DeepestPoint dp = deepest_point(hm, c, a, p.wheel_radius, p.tyre_tube_radius());
    // Contact frame of Fig. 7: x forward (yawed with the wheel, not tilted), y along the axle
    // projected on the terrain, z the terrain normal.
    const Vec3 n = dp.normal;
    Vec3 fx = a.cross(n);
    const double fx_norm = fx.norm();
    fx = fx_norm > 1e-9 ? Vec3(fx * (1.0 / fx_norm)) : Vec3(rot(parent_of(i)).col(0));
    g.n = n;
    g.fx = fx;
    g.fy = n.cross(fx);
    g.axle = a;
    if (!(dp.depth > 0.0)) continue;
    g.active = true;
    g.point = dp.point;
    g.arm = dp.point - c;
    g.depth = dp.depth;
    st.sinkage[i] = dp.depth;
    const Vec3 vc = to_vec(dBodyGetLinearVel(wb));
    dVector3 vp;
    dBodyGetPointVel(wb, dp.point.x(), dp.point.y(), dp.point.z(), vp);
    st.contact_vx[i] = to_vec(vp).dot(g.fx);
    st.contact_vy[i] = to_vec(vp).dot(g.fy);
    if (!soft) continue;
    // Bekker–Wong (eqs 12–32) split into what ODE integrates implicitly and the rest:
    // (a) the shear, whose regularisation tau -> sign(-v_c) min(|v_c|/eps_contact, 1) tau
    //     (eqs 28–29) is a viscous law with a force cap: friction rows at the contact point with
    //     force-dependent slip (velocity = slip * force) and bounds +-F_sat;
    // (b) the compaction resistance -sign(v_x) rb int sigma sin (eq 30), whose regularised sign
    //     clamp(v_x / eps_direction) is the same kind of law on the wheel-centre velocity: a
    //     linear-motor row with CFM = eps_direction / F and bounds +-F;
    // (c) the normal force (eq 32, with the shear's normal part at last step's level) as the
    //     target of the contact's normal row, a damper that never pulls: F_n = max(0, F_z - c v_n);
    // (d) explicit: the share of the axle torque the rows do not produce, at last step's levels.
    // Treated explicitly, (a) and (b) are stiff dampers (~1e4 N s/m) unstable at any useful step.
    const double vx = vc.dot(g.fx);
    // The model uses sign(v_x) exactly; at v_x = 0 the sign is taken as +.
    const soil::ContactState cs{dp.depth, vx != 0.0 ? vx : 1e-12, vc.dot(g.fy), st.contact_vx[i],
                                st.contact_vy[i]};
    const soil::SoilSplit s = soil.split(cs);
    st.slip[i] = s.slip;
    g.ax = std::max(s.fx_shear, 0.0);
    g.ay = std::max(s.fy_shear, 0.0);
    const double sign_vx = cs.vx > 0.0 ? 1.0 : -1.0;
    g.comp = std::max(-s.fx_pressure * sign_vx, 0.0);  // rb int sigma sin theta (eq 30)
    if (g.comp < kMinRowBound) g.comp = 0.0;
    const double sx = shear_x[i];
    g.fz = std::max(0.0, s.fz_pressure) + s.fz_shear * sx;
    const double arm = g.arm.cross(g.fx).dot(a);  // axle torque per unit x force at the patch
    const double row_torque = arm * g.ax * sx;
    const double soil_torque = -s.torque_shear * sx;  // the soil applies -axle_torque
    // The compaction row acts at the wheel centre; its moment about the axle (at the patch) is
    // added with last step's level.
    base_torque[2 + i] += a * (soil_torque - row_torque + arm * compaction[i]);
  }
}

void RoverSim::Impl::near(dGeomID a, dGeomID b) {
  dContact cs[kMaxContactsPerPair];
  std::memset(cs, 0, sizeof cs);
  const int n = dCollide(a, b, kMaxContactsPerPair, &cs[0].geom, sizeof(dContact));
  if (n <= 0) return;
  const double erp = opt.rigid.erp(opt.dt);
  // The §3.4 stiffness is per wheel–obstacle contact: n simultaneous points share it.
  const double cfm = opt.rigid.cfm(opt.dt) * n;
  for (int k = 0; k < n && n_obstacle_contacts < kMaxObstacleContacts; ++k) {
    dContact& c = obstacle_contact[n_obstacle_contacts];
    c = cs[k];
    c.surface.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM | dContactSlip1 |
                     dContactSlip2;
    c.surface.slip1 = c.surface.slip2 = opt.rigid_slip;
    c.surface.mu = mu;
    c.surface.soft_erp = erp;
    c.surface.soft_cfm = cfm;
    obstacle_bodies[2 * n_obstacle_contacts] = dGeomGetBody(a);
    obstacle_bodies[2 * n_obstacle_contacts + 1] = dGeomGetBody(b);
    ++n_obstacle_contacts;
  }
}

void RoverSim::Impl::prepare_obstacles() {
  n_obstacle_contacts = 0;
  if (obstacle_geoms.empty()) return;
  // Never let an exception cross ODE's C callback: capture it and rethrow after the collision.
  dSpaceCollide2(
      reinterpret_cast<dGeomID>(rover_space), reinterpret_cast<dGeomID>(obstacle_space), this,
      [](void* data, dGeomID a, dGeomID b) {
        auto* self = static_cast<Impl*>(data);
        if (self->callback_error) return;
        try {
          self->near(a, b);
        } catch (...) {
          self->callback_error = std::current_exception();
        }
      });
  if (callback_error) {
    std::exception_ptr e = callback_error;
    callback_error = nullptr;
    std::rethrow_exception(e);
  }
}

// Drive k (wheels 0..3, yaw, roll): its guessed row, its axis and the bodies it acts between.
RoverSim::Impl::DriveRow RoverSim::Impl::drive_row(int k) const {
  if (k < 4) return {kRowsPerWheel * k + kWheelMotor, ground[k].axle, 2 + k, parent_of(k)};
  return {kYawMotor + (k - 4), k == 4 ? yaw_axis : roll_axis, kChassis, kBogie};
}

// Rigid ground (§3.4) under wheel i: the contact's rows are guessed like the soil's. Normal at 0
// (separating): no contact at all. Normal pushing and both friction rows inside mu times it
// (sticking, the rolling wheel's usual case): three unbounded rows. A friction row at its bound
// (sliding): ODE's own contact with its bounds, because the bound, mu times the normal force, is
// itself unknown, so no explicit force can stand for it.
RoverSim::Impl::RigidEmit RoverSim::Impl::rigid_emit(const std::int8_t* modes, int wheel) const {
  if (!modes) return RigidEmit::Bounded;
  const std::int8_t* m = modes + kRowsPerWheel * wheel;
  if (m[kNormal] == kAtLo) return RigidEmit::None;
  if (m[kNormal] == kFree && m[kShearX] == kFree && m[kShearY] == kFree) return RigidEmit::Guessed;
  return RigidEmit::Bounded;
}

// One unbounded velocity row lambda = (motion - v . dir) / cfm, v the velocity of `point` on the
// wheel body b (dir unit). ODE's DBall joint is the one joint made of a single unbounded row at
// a chosen point and direction: anchors at the point and a distance L behind it along dir; with
// ERP = 1 its right-hand side is (target distance - distance) / dt, so a target of L + motion dt
// gives the motion (L > 2 |motion| dt keeps the target positive, as ODE requires). Unlike a
// contact's friction row it brings no slack normal row along.
void RoverSim::Impl::add_row(dBodyID b, const Vec3& point, const Vec3& dir, double motion,
                             double cfm, dJointFeedback* fb) {
  const double behind = 1.0 + 2.0 * std::abs(motion) * opt.dt;
  const Vec3 a2 = point - behind * dir;
  dJointID j = dJointCreateDBall(world, contacts);
  dJointAttach(j, b, nullptr);
  dJointSetDBallAnchor1(j, point.x(), point.y(), point.z());
  dJointSetDBallAnchor2(j, a2.x(), a2.y(), a2.z());
  dJointSetDBallDistance(j, behind + motion * opt.dt);
  dJointSetDBallParam(j, dParamERP, 1.0);
  dJointSetDBallParam(j, dParamCFM, cfm);
  if (fb) dJointSetFeedback(j, fb);
}

// Joints and forces of one attempt. modes == nullptr: every guessed row with its bounds.
void RoverSim::Impl::emit(const std::int8_t* modes) {
  std::array<Vec3, 6> f = base_force, t = base_torque;
  const auto mode_of = [&](int row) { return modes ? modes[row] : kBounded; };
  // ---- drives
  for (int k = 0; k < 6; ++k) {
    const MotorRow& m = motor[k];
    const DriveRow d = drive_row(k);
    const int row = d.row;
    const std::int8_t mode = m.bound > 0.0 ? mode_of(row) : kBounded;
    double fmax = m.bound;
    if (mode == kFree) fmax = dInfinity;
    if (mode == kAtHi || mode == kAtLo) {
      fmax = 0.0;
      const double lambda = mode == kAtHi ? m.bound : -m.bound;
      t[d.body1] += d.axis * lambda;
      t[d.body2] -= d.axis * lambda;
    }
    // (only what changed: the joints keep their parameters between steps)
    const dJointID jm = k < 4 ? wheel_motor[k] : gimbal_motor;
    if (!(motor_set[k][0] == m.target)) {
      dJointSetAMotorParam(jm, k == 5 ? dParamVel2 : dParamVel, m.target);
      motor_set[k][0] = m.target;
    }
    if (!(motor_set[k][1] == fmax)) {
      dJointSetAMotorParam(jm, k == 5 ? dParamFMax2 : dParamFMax, fmax);
      motor_set[k][1] = fmax;
    }
  }
  // ---- ground
  // The x and y rows at the patch are the friction rows of an ODE contact with the terrain
  // normal n (fdir1 = x, then n × x = y), whose own normal row carries the normal force when that
  // is solved with its bound (>= 0). When the normal force is guessed positive it is an
  // unbounded row instead (add_row) and the contact's normal row is kept slack.
  const bool soft = opt.ground == GroundType::Soil;
  struct Slot {
    Vec3 dir;
    double mu, slip, motion;
  };
  const double rigid_erp = opt.rigid.erp(opt.dt), rigid_cfm = opt.rigid.cfm(opt.dt);
  for (int i = 0; i < 4; ++i) {
    const GroundContact& g = ground[i];
    if (!g.active) continue;
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
      dJointID j = dJointCreateContact(world, contacts, &cj);
      dJointAttach(j, wb, nullptr);
      if (fb) dJointSetFeedback(j, fb);
    };
    if (!soft) {
      const RigidEmit how = rigid_emit(modes, i);
      if (how == RigidEmit::None) continue;
      if (how == RigidEmit::Guessed) {
        // The §3.4 spring–damper as ODE's normal row would apply it (lambda = (erp depth / dt
        // - v_n) / cfm), and sticking friction rows with the contact's slip.
        const Slot xy[2] = {{g.fx, dInfinity, opt.rigid_slip, 0.0},
                            {g.fy, dInfinity, opt.rigid_slip, 0.0}};
        make(g.n, -kSlackSpeed, rigid_cfm, xy, 2, &ground_fb[i]);
        add_row(wb, g.point, g.n, rigid_erp * g.depth / opt.dt, rigid_cfm, &ground_fb_l[i]);
        continue;
      }
      dContact ct;
      std::memset(&ct, 0, sizeof ct);
      for (int k = 0; k < 3; ++k) {
        ct.geom.pos[k] = g.point[k];
        ct.geom.normal[k] = g.n[k];
      }
      // Coulomb friction mu (pyramid): ODE bounds these rows by mu times the normal force found
      // before them (findex), an order-dependent approximation of Coulomb's law.
      for (int k = 0; k < 3; ++k) ct.fdir1[k] = g.fx[k];
      ct.geom.depth = g.depth;
      ct.surface.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM | dContactSlip1 |
                        dContactSlip2 | dContactFDir1;
      ct.surface.mu = mu;
      ct.surface.slip1 = ct.surface.slip2 = opt.rigid_slip;
      ct.surface.soft_erp = rigid_erp;
      ct.surface.soft_cfm = rigid_cfm;
      dJointID j = dJointCreateContact(world, contacts, &ct);
      dJointAttach(j, wb, nullptr);
      dJointSetFeedback(j, &ground_fb[i]);
      continue;
    }
    // Soft soil.
    // (c) Normal force F_n = max(0, F_z - c v_n): a damper around the soil's pressure force that
    //     never pulls; lambda = (motion - v_n) / cfm with motion = F_z / c, cfm = 1 / c. Guessed
    //     at 0 (the wheel leaves the soil faster than F_z / c): no row, no force.
    const double c = opt.soil_normal_damping;
    const std::int8_t normal_mode = mode_of(kRowsPerWheel * i + kNormal);
    Slot slots[2];  // x then y: with fdir1 = x the second friction row is n × x = y
    int ns = 0;
    bool x_row = false;
    // (a) Shear rows: at a guessed bound, explicit forces at the patch.
    for (int k = 0; k < 2; ++k) {
      const double bound = k == 0 ? g.ax : g.ay;
      if (bound < kMinRowBound) continue;
      const Vec3& dir = k == 0 ? g.fx : g.fy;
      const std::int8_t mode = mode_of(kRowsPerWheel * i + (k == 0 ? kShearX : kShearY));
      if (mode == kAtHi || mode == kAtLo) {
        add_at(f[2 + i], t[2 + i], dir * (mode == kAtHi ? bound : -bound), g.arm);
        continue;
      }
      const double slip = (k == 0 ? opt.soil.eps_contact_x : opt.soil.eps_contact_y) / bound;
      slots[ns++] = Slot{dir, mode == kFree ? dInfinity : bound, slip, 0.0};
      x_row = x_row || k == 0;
    }
    if (normal_mode == kFree && !x_row) {
      // Normal force and at most the y row: one contact whose "normal" is x (kept slack), the
      // normal force as its friction row along n, y as its second (x × n = -y).
      Slot l[2] = {{g.n, dInfinity, 1.0 / c, g.fz / c}};
      if (ns > 0) l[1] = slots[0];
      make(g.fx, -kSlackSpeed, 1.0 / c, l, 1 + ns, nullptr);
    } else {
      // The contact along n with the x (and y) rows, its normal row bounded or slack, and a
      // guessed normal force as its own row (two contacts would bring two slack rows).
      if (normal_mode == kFree) add_row(wb, g.point, g.n, g.fz / c, 1.0 / c, nullptr);
      if (normal_mode == kBounded || ns > 0)
        make(g.n, normal_mode == kBounded ? g.fz / c : -kSlackSpeed, 1.0 / c, slots, ns,
             &ground_fb[i]);
    }
    // (b) Compaction row on the wheel centre.
    if (g.comp > 0.0) {
      const std::int8_t mode = mode_of(kRowsPerWheel * i + kCompaction);
      if (mode == kAtHi || mode == kAtLo) {
        f[2 + i] += g.fx * (mode == kAtHi ? g.comp : -g.comp);
      } else {
        const double eps_dir = std::max(opt.soil.eps_direction, 1e-6);
        dJointID lm = dJointCreateLMotor(world, contacts);
        dJointAttach(lm, wb, nullptr);
        dJointSetLMotorNumAxes(lm, 1);
        dJointSetLMotorAxis(lm, 0, 0, g.fx.x(), g.fx.y(), g.fx.z());
        dJointSetLMotorParam(lm, dParamVel, 0.0);
        dJointSetLMotorParam(lm, dParamFMax, mode == kFree ? dInfinity : g.comp);
        dJointSetLMotorParam(lm, dParamCFM, eps_dir / g.comp);
      }
    }
  }
  // ---- rigid obstacles (always with their bounds: friction limits depend on the normal force)
  for (int k = 0; k < n_obstacle_contacts; ++k) {
    dJointID j = dJointCreateContact(world, contacts, &obstacle_contact[k]);
    dJointAttach(j, obstacle_bodies[2 * k], obstacle_bodies[2 * k + 1]);
  }
  for (int b = 0; b < 6; ++b) {
    dBodySetForce(body[b], f[b].x(), f[b].y(), f[b].z());
    dBodySetTorque(body[b], t[b].x(), t[b].y(), t[b].z());
  }
  check_forces_before_step();
}

// Rigid ground under wheel i after the step: the contact's forces (from the joints' feedback) and
// where Coulomb's law puts each row (next[]). Returns false if a guess was wrong: a guessed
// contact whose normal force is negative or whose friction exceeds mu times it, or a missing one
// that the spring–damper would push. A contact ODE solved with its bounds is right by
// construction: only its outcome is recorded.
bool RoverSim::Impl::settle_rigid(int i, const std::int8_t* modes, const Vec3& vp,
                                  std::int8_t* next) {
  const GroundContact& g = ground[i];
  const int r = kRowsPerWheel * i;
  const RigidEmit how = rigid_emit(modes, i);
  if (how == RigidEmit::None) {
    const double push = opt.rigid.erp(opt.dt) * g.depth / opt.dt - vp.dot(g.n);
    next[r + kNormal] = push > 0.0 ? kFree : kAtLo;
    next[r + kShearX] = next[r + kShearY] = kFree;
    return push <= 0.0;
  }
  Vec3 f = to_vec(ground_fb[i].f1);
  if (how == RigidEmit::Guessed) f += to_vec(ground_fb_l[i].f1);
  const double fn = f.dot(g.n), fx = f.dot(g.fx), fy = f.dot(g.fy);
  row_force[r + kNormal] = fn;
  row_force[r + kShearX] = fx;
  row_force[r + kShearY] = fy;
  const double cap = mu * std::max(fn, 0.0);
  next[r + kNormal] = fn > 0.0 ? kFree : kAtLo;
  if (how == RigidEmit::Guessed) {
    // The check is exact: |lambda| <= mu F_n. The outcome for the next step leaves a margin:
    // friction near its cap is about to slide, and a failed guess costs a second step.
    const bool ok = std::abs(fx) <= cap && std::abs(fy) <= cap;
    next[r + kShearX] = status_of(fx, kStickMargin * cap);
    next[r + kShearY] = status_of(fy, kStickMargin * cap);
    if (!ok || !(fn > 0.0)) return false;
    return true;
  } else {
    // ODE bounded these rows by mu times the normal force it had when it clamped them, which can
    // be 30 % off the final one, so the force does not tell sliding from sticking; the slip
    // velocity does: a row whose law lambda = -v_t / slip exceeds the bound is sliding.
    const auto law = [&](const Vec3& dir) {
      const double v = vp.dot(dir);
      return opt.rigid_slip > 0.0 ? -v / opt.rigid_slip : (v == 0.0 ? 0.0 : -v * dInfinity);
    };
    next[r + kShearX] = status_of(law(g.fx), cap);
    next[r + kShearY] = status_of(law(g.fy), cap);
  }
  if (how == RigidEmit::Bounded) return true;
  return next[r + kNormal] == kFree && next[r + kShearX] == kFree && next[r + kShearY] == kFree;
}

// After dWorldStep: the force of every guessed row and where its law puts it (next[]); returns
// whether every guess held. The laws are evaluated with the Jacobians of the start of the step
// (as ODE built them) and the velocities at its end.
bool RoverSim::Impl::settle(const std::int8_t* modes, std::int8_t* next) {
  bool held = true;
  const auto mode_of = [&](int row) { return modes ? modes[row] : kBounded; };
  const auto outcome = [&](int row, std::int8_t status) {
    const std::int8_t m = mode_of(row);
    if (m != kBounded && m != status) held = false;
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
    const std::int8_t mode = mode_of(row);
    if (mode == kAtHi || mode == kAtLo) {
      const double rate = (to_vec(dBodyGetAngularVel(body[d.body1])) -
                           to_vec(dBodyGetAngularVel(body[d.body2]))).dot(axis);
      const double demand = (m.target - rate) / kWorldCfm;  // the row's unclamped force
      row_force[row] = mode == kAtHi ? m.bound : -m.bound;
      outcome(row, status_of(demand, m.bound) == mode ? mode : kFree);
    } else {
      const dJointFeedback& fb = k < 4 ? wheel_motor_fb[k] : gimbal_motor_fb;
      const double lambda = to_vec(fb.t1).dot(axis);
      row_force[row] = std::clamp(lambda, -m.bound, m.bound);
      // A bounded row that ODE left at its bound is at it; a free row beyond it is not free.
      outcome(row, mode == kBounded ? (std::abs(lambda) < m.bound ? kFree : status_of(lambda, m.bound))
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
    {  // normal force >= 0, F_z - c v_n at the patch: the row's law, or ODE's bounded row
      const int row = kRowsPerWheel * i + kNormal;
      const std::int8_t mode = mode_of(row);
      if (mode == kBounded) {
        row_force[row] = to_vec(ground_fb[i].f1).dot(g.n);
        outcome(row, row_force[row] > 0.0 ? kFree : kAtLo);
      } else {
        const double total = g.fz - opt.soil_normal_damping * vp.dot(g.n);
        row_force[row] = mode == kFree ? total : 0.0;
        outcome(row, total > 0.0 ? kFree : kAtLo);
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
      const std::int8_t mode = mode_of(row);
      row_force[row] = mode == kAtHi ? r.bound
                       : mode == kAtLo ? -r.bound
                                       : std::clamp(r.u, -r.bound, r.bound);
      outcome(row, status_of(r.u, r.bound));
    }
  }
  return held;
}

void RoverSim::Impl::save_bodies() {
  for (int b = 0; b < 6; ++b) {
    const dBodyID id = body[b];
    const dReal *x = dBodyGetPosition(id), *q = dBodyGetQuaternion(id),
                *v = dBodyGetLinearVel(id), *w = dBodyGetAngularVel(id);
    for (int k = 0; k < 3; ++k) {
      saved[b].pos[k] = x[k];
      saved[b].lin[k] = v[k];
      saved[b].ang[k] = w[k];
    }
    for (int k = 0; k < 4; ++k) saved[b].quat[k] = q[k];
  }
}

void RoverSim::Impl::restore_bodies() {
  for (int b = 0; b < 6; ++b) {
    const dBodyID id = body[b];
    const auto& s = saved[b];
    const dQuaternion q = {s.quat[0], s.quat[1], s.quat[2], s.quat[3]};
    dBodySetPosition(id, s.pos[0], s.pos[1], s.pos[2]);
    dBodySetQuaternion(id, q);  // canonical (read_outputs): set returns it bit for bit
    dBodySetLinearVel(id, s.lin[0], s.lin[1], s.lin[2]);
    dBodySetAngularVel(id, s.ang[0], s.ang[1], s.ang[2]);
  }
}

void RoverSim::Impl::step() {
  if (diverged)
    throw SimulationDiverged("RoverSim: the simulation diverged earlier; restore() or reset() first");
  init_ode_once();
  double psi = start_psi, phi = start_phi;
  if (!start_current) {  // the bodies changed since read_outputs() (restore)
    double psid, phid;
    gimbal_angles(psi, phi, psid, phid, yaw_axis, roll_axis);
  }
  start_current = false;
  base_force.fill(Vec3::Zero());
  base_torque.fill(Vec3::Zero());
  prepare_actuators(psi, phi);
  prepare_ground();
  prepare_obstacles();
  base_force[kChassis] += pending_force;
  pending_force.setZero();
  save_bodies();

  // ODE aborts the process (an assertion in its quaternion normalisation) when a step produces a
  // non-finite state, so emit() refuses absurd forces before stepping; check_divergence() then
  // only has to catch finite but absurd states. dWorldStep (Dantzig), not dWorldQuickStep:
  // QuickStep reorders constraints with ODE's process-wide random generator (not reproducible).
  // Guesses in turn: the last step's outcome; the outcome two steps back (a period-2 chatter,
  // e.g. a stuck wheel's v_x changing sign every step, defeats the first; once it held, it goes
  // first); then the last attempt's outcome. After kMaxGuesses wrong guesses every row whose
  // guess failed is solved with its bounds instead (ODE pivots it, and a bounded row cannot be
  // wrong), attempt after attempt: each adds at least one bounded row, so this ends.
  const bool chatter = alternating && row_mode_before != row_mode;
  std::array<std::int8_t, kGuessedRowCount> guess = chatter ? row_mode_before : row_mode;
  std::array<std::int8_t, kGuessedRowCount> next = guess, tried = guess;
  int attempts = 0;
  bool held = false;
  alternating = false;
  const std::uint64_t lcp_messages = ode_lcp_messages;
  while (opt.guess_active_set && !held && attempts < kMaxGuesses + kGuessedRowCount) {
    if (attempts++ > 0) restore_bodies();
    tried = guess;
    emit(guess.data());
    dWorldStep(world, opt.dt);
    held = settle(guess.data(), next.data());
    dJointGroupEmpty(contacts);
    if (held) {
      alternating = guess == row_mode_before && row_mode_before != row_mode;
      break;
    }
    if (attempts == 1 && row_mode_before != row_mode) {
      guess = chatter ? row_mode : row_mode_before;
      continue;
    }
    for (int r = 0; r < kGuessedRowCount; ++r) {
      if (attempts >= kMaxGuesses) {
        guess[r] = tried[r] != kBounded && next[r] != tried[r] ? kBounded : tried[r];
      } else {
        // Where each row's law put it; a row that jumped from one bound to the other (its
        // velocity changed sign within the step) is most likely between them.
        const bool flipped = (tried[r] == kAtHi && next[r] == kAtLo) ||
                             (tried[r] == kAtLo && next[r] == kAtHi);
        guess[r] = flipped ? kFree : next[r];
      }
    }
  }
  if (!held) {  // guessing off (or, never seen, no progress): every row with its bounds
    if (attempts++ > 0) restore_bodies();
    emit(nullptr);
    dWorldStep(world, opt.dt);
    settle(nullptr, next.data());
    dJointGroupEmpty(contacts);
  }
  row_mode_before = row_mode;
  row_mode = next;
  ++stats.steps;
  if (ode_lcp_messages != lcp_messages) ++stats.lcp_errors;
  if (opt.guess_active_set) {
    const bool some_bounded = std::find(tried.begin(), tried.end(), kBounded) != tried.end();
    if (held && attempts == 1) ++stats.first_guess;
    else if (held && !some_bounded) ++stats.later_guess;
    else ++stats.pivoted;
  }
  read_outputs(opt.dt);
  check_divergence();
}

void RoverSim::Impl::read_outputs(double dt) {
  for (auto b : body) canonicalise_quaternion(b);
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
    st.wheel_load[i] = 0.0;
    shear_x[i] = shear_y[i] = compaction[i] = 0.0;
    if (dt > 0.0 && g.active) {
      st.wheel_load[i] = row_force[kRowsPerWheel * i + kNormal];
      if (opt.ground == GroundType::Soil) {
        shear_x[i] = g.ax >= kMinRowBound ? clamp_unit(row_force[kRowsPerWheel * i + kShearX] / g.ax) : 0.0;
        shear_y[i] = g.ay >= kMinRowBound ? clamp_unit(row_force[kRowsPerWheel * i + kShearY] / g.ay) : 0.0;
        compaction[i] = row_force[kRowsPerWheel * i + kCompaction];
      }
    }
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
    std::string what;
    if (!x.allFinite() || !v.allFinite() || !w.allFinite()) {
      what = "non-finite state";
    } else if (v.squaredNorm() > opt.max_speed * opt.max_speed) {
      what = "speed " + std::to_string(v.norm()) + " m/s > max_speed " + std::to_string(opt.max_speed);
    } else if (w.squaredNorm() > opt.max_angular_speed * opt.max_angular_speed) {
      what = "angular speed " + std::to_string(w.norm()) + " rad/s > max_angular_speed " +
             std::to_string(opt.max_angular_speed);
    } else if (x.squaredNorm() > 1e12) {
      what = "position beyond 1e6 m";
    }
    if (!what.empty()) {
      diverged = true;
      std::ostringstream os;
      os << "SimulationDiverged at t = " << st.time << " s: " << kBodyNames[b] << " " << what
         << " (dt = " << opt.dt << " s); restore a snapshot or reset";
      throw SimulationDiverged(os.str());
    }
  }
}

}  // namespace ernest::dynamics
