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
// guesses), then the rows whose guesses keep failing are handed to ODE with their bounds.
// This file: the step's set-up (actuators, ground) and the attempt loop; rover_slip.cpp: the soil's
// terms at a slip and the implicit slip's first guesses; obstacle_contacts.cpp:
// the obstacles' contacts and the substeps of a step that touches one (step());
// rover_rows.cpp: emitting and checking the rows; rover_outputs.cpp: what the step reports.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include <Eigen/LU>

#include "ernest/dynamics/rover_sim_impl.hpp"

namespace ernest::dynamics {

using namespace detail;

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
  const double dt = h;
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
    const double vx = vc.dot(g.fx);
    // The model uses sign(v_x) exactly; at v_x = 0 the sign is taken as +.
    g.cs = soil::ContactState{dp.depth, vx != 0.0 ? vx : 1e-12, vc.dot(g.fy), st.contact_vx[i],
                              st.contact_vy[i]};
    // First guess of the step's slip: eq 12 at the start of the step (see step()).
    const double slip0 = soil.slip_ratio(g.cs.vx, g.cs.vcx);
    soil_terms(i, slip0);
    // The pressure-sinkage spring of eq 32 linearised in the sinkage, for the normal row
    // (rover_rows.cpp): F_z(z - h v_n) ~ F_z - h (dF_z/dz) v_n, a backward-Euler damper added to
    // the soil's. Taken at the start of the step instead, the spring against the damper (time
    // constant ~50 ms) lagged a step: benchmarks/RESULTS.md, "step independence". dF_z/dz comes
    // with the split (eq 17 differentiated, SoilSplit::dfz_pressure_dh: closer to the exact
    // derivative than a difference, at no extra quadrature); for n < 1 its integrand is singular
    // at the ends, and a forward difference over 1 % of the sinkage serves instead.
    double ks = 0.0;
    if (soil.soil().sinkage_exponent >= 1.0) {
      ks = std::max(0.0, soil_split(i, slip0).dfz_pressure_dh);
    } else {
      soil::ContactState deeper = g.cs;
      const double dz = std::max(1e-5, 0.01 * dp.depth);
      deeper.sinkage += dz;
      ks = std::max(0.0, (soil.split_pressure(deeper, st.slip[i]).fz_pressure - g.fz_pressure) / dz);
    }
    g.normal_damping = opt.soil_normal_damping + h * ks;
  }
}

// One solve of the step at the current soil terms: the guessed rows (guess: in; next: where the
// rows' laws put them; tried: the last guess emitted), retried as described in step(). Returns
// whether a guess held (false: the rows were solved with their bounds, or guessing is off).
bool RoverSim::Impl::solve_rows(RowStates& guess, RowStates& next, RowStates& tried,
                                int& attempts) {
  bool held = false;
  while (opt.guess_active_set && !held && attempts < RowGuesser::kMaxAttempts) {
    if (attempts++ > 0) restore_bodies();
    tried = guess;
    emit(RowModes::guess(guess));
    world_step();
    held = settle(RowModes::guess(guess), next);
    dJointGroupEmpty(contacts);
    if (held) {
      guesser.held(guess);
      break;
    }
    if (guesser.other_outcome(attempts, rows_held, tried, guess)) continue;
    guess = RowGuesser::next_guess(attempts, tried, next);
  }
  if (!held) {  // guessing off (or, never seen, no progress): every row with its bounds
    if (attempts++ > 0) restore_bodies();
    obstacle_try.fill(RowState::Bounded);
    emit(RowModes::all_bounded());
    world_step();
    settle(RowModes::all_bounded(), next);
    dJointGroupEmpty(contacts);
  }
  return held;
}

// The attempt's contacts and linear motors are recorded by the island step for either stepper;
// for dWorldStep, world_step() creates them in ODE (IslandStep::materialise) in the same order.
// Every attempt's joints fit: four ground contacts, four compaction motors, the obstacles'.
static_assert(kMaxObstacleContacts + 8 <= solver::IslandStep::kMaxAttemptJoints,
              "IslandStep must record every joint of an attempt");

void RoverSim::Impl::add_contact_joint(const dContact& c, dBodyID b1, dBodyID b2,
                                       dJointFeedback* fb) {
  island.add_contact(c, b1, b2, fb);
}

void RoverSim::Impl::add_lmotor_joint(dBodyID b, const Vec3& axis, double fmax, double cfm) {
  const double a[3] = {axis.x(), axis.y(), axis.z()};
  island.add_lmotor(b, a, 0.0, fmax, cfm);
}

// One attempt's step of the bodies. Own: our island step (solver/island_step.hpp); where it does not
// reproduce dWorldStep it changes nothing, and the attempt's joints are created in ODE for
// dWorldStep (with the sparse path off when our solve already found it cannot: ODE's Dantzig
// solver then, as the hook would have gone).
void RoverSim::Impl::world_step() {
  quaternions_fixed = false;
  if (opt.stepper != Stepper::Own) {
    island.materialise(world, contacts);
    dWorldStep(world, h);
    return;
  }
  const solver::IslandStep::Outcome r =
      opt.resolve_rhs_only ? island.resolve(world, h, lcp) : island.step(world, h, lcp);
  using Outcome = solver::IslandStep::Outcome;
  if (r == Outcome::Stepped || r == Outcome::Resolved || r == Outcome::ResolvedCaps) {
    ++stats.own_steps;
    if (r == Outcome::Resolved) ++stats.rhs_resolves;
    if (r == Outcome::ResolvedCaps) ++stats.cap_resolves;
    quaternions_fixed = island.quaternions_fixed();
    return;
  }
  ++stats.own_fallbacks;
  island.materialise(world, contacts);
  const bool enabled = lcp.enabled;
  if (r == solver::IslandStep::Outcome::SolveRefused) lcp.enabled = false;
  dWorldStep(world, h);
  lcp.enabled = enabled;
}

void RoverSim::Impl::step_once() {
  if (diverged)
    throw SimulationDiverged("RoverSim: the simulation diverged earlier; restore() or reset() first");
  solver::init_ode_once();
  island.forget();  // a new step: the joints' parameters change (stops, drives), resolve() may not
  double psi = start_psi, phi = start_phi;
  if (!start_current) {  // the bodies changed since read_outputs() (restore)
    double psid, phid;
    gimbal_angles(psi, phi, psid, phid, yaw_axis, roll_axis);
  }
  start_current = false;
  base_force.fill(Vec3::Zero());
  base_torque.fill(Vec3::Zero());
  prepare_actuators(psi, phi);
  const std::array<double, 4> start_x = shear_x, start_c = compaction;
  warm_start_levels();
  prepare_ground();
  if (opt.ground == GroundType::Rigid) prepare_rigid();
  if (!obstacles_collected) prepare_obstacles();
  obstacles_collected = false;
  base_force[kChassis] += pending_force;
  pending_force.setZero();
  save_bodies();

  // ODE aborts the process (an assertion in its quaternion normalisation) when a step produces a
  // non-finite state, so emit() refuses absurd forces before stepping; check_divergence() then
  // only has to catch finite but absurd states. dWorldStep (Dantzig), not dWorldQuickStep:
  // QuickStep reorders constraints with ODE's process-wide random generator (not reproducible).
  // The guesses in turn (RowGuesser, row_guess.hpp): the last step's outcome, the one two steps
  // back, the last attempt's; then the failing rows solved with their bounds (ODE pivots them,
  // and a bounded row cannot be wrong).
  RowStates guess = guesser.first_guess();
  RowStates next = guess, tried = guess;
  const std::uint64_t lcp_messages = solver::ode_lcp_messages;
  const solver::LcpScope lcp_scope(&lcp);
  obstacle_try = obstacle_mode;
  obstacle_off = 0;

  // Implicit slip (backward Euler in eq 12). Where the wheel centre barely moves the slip is a
  // steep function of its velocity (on the eps_slip^-1/2 = 1 cm/s scale of eq 12's factor; see
  // SoilParameters::slip_clamp_first), and the soil's force changes by ~150 N between s = 0 and
  // s = -1: as a damper ~1e4 N s/m per wheel. With the slip taken from the start of the step
  // (explicit) that turns into a period-2 chatter at every usable step, whose mean creep moves
  // with the step (benchmarks/RESULTS.md, "step independence"). So a step is solved with slips
  // sigma (one per wheel) and accepted when eq 12 at its end velocities gives back sigma, to
  // within SimOptions::slip_force_tolerance of the soil forces the slip sets (soil_terms_gap:
  // a slip error where the forces do not depend on it costs no solve), or when the slips agree
  // to kSlipTolerance. The soil rows' levels that the explicit terms use are updated from each
  // solve (a fixed point alongside the slip) and their change counts in the same force gap.
  // The wheels share the chassis, so the residual r(sigma) = s_end - sigma
  // couples them: Broyden's method on the four slips from J = -I (the first update is the
  // fixed-point step, eq 12 at the end), clamped to [-1, 1], from the first guesses of
  // warm_start_levels / warm_start_slips. After kMaxSlipSolves solves the step is solved once
  // more at the best slips seen. Once every solved slip agrees with eq 12 to kSlipTolerance, only
  // the levels are off (the acceptance test already ignores such a slip error): sigma is then
  // kept and the levels alone iterated. Broyden would still move sigma a little, and with it the
  // soil rows' caps and force-dependent CFMs; kept, the re-solve is the last attempt's system
  // with a new right-hand side (the normal rows' targets, the explicit torques), which the island
  // step solves with the last attempt's rows and factor (IslandStep::resolve). A slip that
  // drifts past kSlipTolerance as the levels move brings Broyden back.
  // Backward Euler is right where the slip damps the motion (the stalled wheel above: a larger
  // slip gives a smaller end slip), not where it drives it. A wheel spinning against an obstacle
  // face on soil stands at v_x ~ 0, where eq 12's factor (1 - exp(-eps v_x^2)) makes the slip, and
  // with it the traction, grow with the forward speed: a negative damper, an unstable rate lambda
  // of a few hundred 1/s. Backward Euler's amplification 1 / (1 - h lambda) is below 1 in magnitude
  // for h lambda > 2 (negative for h lambda > 1), so at the default step it held the wheel at
  // that stall, where fine steps climb the face and fall back (benchmarks/RESULTS.md, "Step
  // size and step independence"). The secant d s_end / d sigma of a wheel's last two solves
  // estimates h lambda; a wheel where it reaches 1 (the step's equation in sigma can then have
  // several roots, and backward Euler reverses or damps the growth) takes its slip from
  // the start of the step (forward Euler: amplification 1 + h lambda, a growing motion grows)
  // and leaves the solve.
  const bool soft = opt.ground == GroundType::Soil;
  Eigen::Vector4d sigma, res = Eigen::Vector4d::Zero();
  for (int i = 0; i < 4; ++i) sigma[i] = st.slip[i];
  const Eigen::Vector4d start_sigma = sigma;  // eq 12 at the start: a driving wheel's slip
  if (soft) warm_start_slips(sigma);
  Eigen::Vector4d best_sigma = sigma, prev_sigma = sigma, prev_res = res;
  Eigen::Matrix4d jac = -Eigen::Matrix4d::Identity();
  Eigen::Vector4d last_sigma = sigma, last_end = sigma;  // each wheel's last solve: sigma, s_end
  std::array<bool, 4> driving{};  // explicit slip: the slip drives this wheel's motion
  double rate = 0.0;  // the largest secant over h: slip_rate (see step() in obstacle_contacts.cpp)
  double best = std::numeric_limits<double>::infinity();
  bool held = false;
  int attempts = 0;
  for (int solve = 0;; ++solve) {
    if (solve > 0) {
      restore_bodies();
      for (int i = 0; i < 4; ++i)
        if (ground[i].active) soil_terms(i, sigma[i]);
      guess = next;
      ++stats.slip_solves;
    }
    attempts = 0;
    held = solve_rows(guess, next, tried, attempts);
    if (!soft || solve > kMaxSlipSolves) break;
    double worst = 0.0;  // [N]: the implicit-slip error as a force (soil_terms_gap)
    bool split = false;  // a wheel left the solve: its start slip needs one more solve
    for (int i = 0; i < 4; ++i) {
      res[i] = 0.0;
      if (!ground[i].active) continue;
      soil_levels(i);  // the levels this solve reached: the next solve's (and step's) terms
      if (driving[i]) continue;
      double vx = 0.0, vcx = 0.0;
      end_velocity(i, vx, vcx);
      const double s_end = soil.slip_ratio(vx, vcx);
      res[i] = s_end - sigma[i];
      const double ds = sigma[i] - last_sigma[i], de = s_end - last_end[i];
      last_sigma[i] = sigma[i];
      last_end[i] = s_end;
      if (solve > 0 && std::abs(ds) > kSlipTolerance) {  // a secant was measured
        rate = std::max(rate, de / (ds * h));
        if (de / ds >= 1.0) {
          driving[i] = split = true;  // h lambda >= 1: see above
          res[i] = 0.0;
          sigma[i] = start_sigma[i];
          continue;
        }
      }
      worst = std::max(worst, soil_terms_gap(i, std::abs(res[i]) > kSlipTolerance ? s_end : sigma[i]));
    }
    if (split) {  // solve again: the driving wheels at their start slips, Broyden afresh
      jac = -Eigen::Matrix4d::Identity();
      prev_sigma = sigma;
      prev_res = res;
      best = std::numeric_limits<double>::infinity();
      continue;
    }
    if (worst <= opt.slip_force_tolerance) break;
    bool converged = true;  // every solved slip agrees with eq 12 to kSlipTolerance
    for (int i = 0; i < 4; ++i)
      converged = converged && (!ground[i].active || driving[i] || std::abs(res[i]) <= kSlipTolerance);
    if (worst < best) {
      best = worst;
      best_sigma = sigma;
    }
    if (solve == kMaxSlipSolves - 1) {  // out of solves: the best seen, once more
      sigma = best_sigma;
      continue;
    }
    if (solve == kMaxSlipSolves) break;
    if (converged) {  // only the levels moved: keep sigma (see above), so the rows stay the same
      prev_sigma = sigma;
      prev_res = res;
      continue;
    }
    if (solve > 0) {  // Broyden's rank-one update with the last change of sigma
      const Eigen::Vector4d ds = sigma - prev_sigma, dr = res - prev_res;
      const double n2 = ds.squaredNorm();
      if (n2 > 0.0) jac += (dr - jac * ds) * ds.transpose() / n2;
    }
    prev_sigma = sigma;
    prev_res = res;
    Eigen::Vector4d step = jac.partialPivLu().solve(-res);
    if (!step.allFinite()) step = res;  // singular: the fixed-point step
    for (int i = 0; i < 4; ++i)
      sigma[i] = ground[i].active && !driving[i] ? std::clamp(sigma[i] + step[i], -1.0, 1.0)
                                                : sigma[i];
  }
  if (soft) record_warm_start(start_x, start_c, sigma, start_sigma, driving);
  if (driving[0] || driving[1] || driving[2] || driving[3]) ++stats.slip_driving;
  slip_rate = rate;
  if (opt.ground == GroundType::Rigid) commit_rigid();
  guesser.commit(next);
  if (n_obstacle_contacts > 0) {
    bool bounded = false;
    for (int k = 0; k < n_obstacle_contacts; ++k)
      bounded = bounded || obstacle_wheel[k] < 0 || obstacle_try[obstacle_wheel[k]] != RowState::Free ||
                !opt.guess_obstacle_contacts;
    ++(bounded ? stats.obstacle_bounded : stats.obstacle_guessed);
    for (int k = 0; k < n_obstacle_contacts; ++k)
      ++(obstacle_explicit[k] ? stats.obstacle_explicit : stats.obstacle_implicit);
  }
  obstacle_mode = obstacle_next;
  ++stats.steps;
  if (solver::ode_lcp_messages != lcp_messages) ++stats.lcp_errors;
  stats.sparse_solves = lcp.sparse;
  stats.dense_solves = lcp.dense;
  stats.plans_made = lcp.plans_made;
  stats.plans_grown = lcp.plans_grown;
  if (opt.guess_active_set) {
    const GuessResult r = RowGuesser::result(held, attempts, tried);
    ++(r == GuessResult::First ? stats.first_guess
       : r == GuessResult::Later ? stats.later_guess : stats.pivoted);
  }
  read_outputs(h);
  check_divergence();
}

}  // namespace ernest::dynamics

