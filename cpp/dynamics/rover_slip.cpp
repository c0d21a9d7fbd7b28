// ERNEST on ODE: the soil's terms of a step at a slip (Bekker–Wong, eqs 12–32 of seed 004, split
// between ODE's rows and explicit forces), the levels the rows reached, and the implicit slip's
// first guesses. The loop that solves a step for its slip is step_once() in rover_step.cpp.
#include <algorithm>
#include <cmath>

#include "ernest/dynamics/rover_sim_impl.hpp"

namespace ernest::dynamics {

using namespace detail;

// First guesses of the implicit slip's fixed point (step_once()), so that most steps are accepted
// after one solve (benchmarks/RESULTS.md, "Where a step goes"). Most of the extra solves
// on obstacles were not for the slip but for the soil rows' levels (shear_x, compaction) the
// explicit terms are evaluated at: the slip agreed with eq 12 to 1e-4 while a level moved by a
// few tenths of a newton from its last step's value, or flipped sign every step where a stalled
// wheel's v_x alternates in sign. So each level starts from whichever of three predictions from
// the last three steps (the last level, its linear extrapolation, the level two steps back)
// would have predicted the last step best. Only a guess: the loop accepts a step when its levels
// and slips agree with the solve's within SimOptions::slip_force_tolerance, as before.
void RoverSim::Impl::warm_start_levels() {
  if (opt.ground != GroundType::Soil || !opt.slip_warm_start) return;
  const auto predict = [](int steps, double l1, double l2, double l3) {
    if (steps < 3) return l1;  // the wheel has not been on soil for three steps: the last level
    const double constant = std::abs(l1 - l2), linear = std::abs(l1 - (2.0 * l2 - l3)),
                 period2 = std::abs(l1 - l3);
    if (constant <= linear && constant <= period2) return l1;
    return linear <= period2 ? 2.0 * l1 - l2 : l2;
  };
  for (int i = 0; i < 4; ++i) {
    shear_x[i] = clamp_unit(predict(soil_steps[i], shear_x[i], shear_x_past[0][i], shear_x_past[1][i]));
    compaction[i] = predict(soil_steps[i], compaction[i], compaction_past[0][i], compaction_past[1][i]);
  }
}

// The slips' first guess: eq 12 at the start of the step (prepare_ground) plus what the last
// step's accepted slip added to its own start value, where the wheel stayed on soil and the
// difference exceeds kSlipTolerance (below it, eq 12's value serves: a guess off by less costs
// no solve, an extra soil split per wheel would). The soil terms are set at the guess.
void RoverSim::Impl::warm_start_slips(Eigen::Vector4d& sigma) {
  if (!opt.slip_warm_start) return;
  for (int i = 0; i < 4; ++i) {
    if (!ground[i].active || !std::isfinite(slip_offset[i])) continue;
    const double guess = std::clamp(sigma[i] + slip_offset[i], -1.0, 1.0);
    if (!(std::abs(guess - sigma[i]) > kSlipTolerance)) continue;
    sigma[i] = guess;
    soil_terms(i, guess);
  }
}

// After a step on soil: the history warm_start_levels / warm_start_slips read (start_x, start_c:
// the levels at the start of the step, before the prediction).
void RoverSim::Impl::record_warm_start(const std::array<double, 4>& start_x,
                                       const std::array<double, 4>& start_c,
                                       const Eigen::Vector4d& sigma,
                                       const Eigen::Vector4d& start_sigma,
                                       const std::array<bool, 4>& driving) {
  for (int i = 0; i < 4; ++i) {
    const bool on = ground[i].active;
    soil_steps[i] = on ? std::min(soil_steps[i] + 1, 3) : 0;
    shear_x_past[1][i] = shear_x_past[0][i];
    shear_x_past[0][i] = start_x[i];
    compaction_past[1][i] = compaction_past[0][i];
    compaction_past[0][i] = start_c[i];
    slip_offset[i] = on && !driving[i] ? sigma[i] - start_sigma[i] : std::nan("");
  }
}

// Bekker–Wong (eqs 12–32) at slip s for wheel i, split into what ODE integrates implicitly and
// the rest:
// (a) the shear, whose regularisation tau -> sign(-v_c) min(|v_c|/eps_contact, 1) tau (eqs
//     28–29) is a viscous law with a force cap: friction rows at the contact point with
//     force-dependent slip (velocity = slip * force) and bounds +-F_sat;
// (b) the compaction resistance -sign(v_x) rb int sigma sin (eq 30), whose regularised sign
//     clamp(v_x / eps_direction) is the same kind of law on the wheel-centre velocity: a
//     linear-motor row with CFM = eps_direction / F and bounds +-F;
// (c) the normal force (eq 32, with the shear's normal part at the shear row's level) as the
//     target of the contact's normal row, a damper that never pulls: F_n = max(0, F_z - c v_n);
// (d) explicit forces: the share of the axle torque the rows do not produce, at the rows' levels.
// The levels (shear_x, compaction) are the step's own: solved together with the slip in step().
// Taken from the previous step instead they lag by one step, and where the rover rocks against an
// obstacle or on a ripple that lag made the energy converge only at first order in the step
// (benchmarks/RESULTS.md, "step independence").
// Treated explicitly, (a) and (b) are stiff dampers (~1e4 N s/m) unstable at any useful step.
// The slip itself is chosen by step() so that it matches eq 12 at the end of the step.
// soil.split(g.cs, slip), memoised for the step (GroundContact::memo_slip): the implicit-slip
// check after a solve usually asks for the slip the solve used.
const soil::SoilSplit& RoverSim::Impl::soil_split(int i, double slip) {
  GroundContact& g = ground[i];
  for (int k = 0; k < 2; ++k)
    if (g.memo_slip[k] == slip) return g.memo_split[k];
  const int k = g.memo_next;
  g.memo_split[k] = soil.split(g.cs, slip);  // throws (memo unchanged) on a non-finite input
  g.memo_slip[k] = slip;
  g.memo_next = 1 - k;
  return g.memo_split[k];
}

RoverSim::Impl::SoilTerms RoverSim::Impl::soil_terms_at(int i, double slip) {
  const GroundContact& g = ground[i];
  const soil::SoilSplit& s = soil_split(i, slip);
  SoilTerms t;
  t.slip = s.slip;
  t.ax = std::max(s.fx_shear, 0.0);
  t.ay = std::max(s.fy_shear, 0.0);
  const double sign_vx = g.cs.vx > 0.0 ? 1.0 : -1.0;
  t.comp = std::max(-s.fx_pressure * sign_vx, 0.0);  // rb int sigma sin theta (eq 30)
  if (t.comp < kMinRowBound) t.comp = 0.0;
  const double sx = shear_x[i];
  t.fz_pressure = s.fz_pressure;
  t.fz = std::max(0.0, s.fz_pressure) + s.fz_shear * sx;
  const double arm = g.arm.cross(g.fx).dot(g.axle);  // axle torque per unit x force at the patch
  const double row_torque = arm * t.ax * sx;
  const double soil_torque = -s.torque_shear * sx;  // the soil applies -axle_torque
  // The compaction row acts at the wheel centre; its moment about the axle (at the patch) is
  // added at the row's level.
  t.axle_torque = soil_torque - row_torque + arm * compaction[i];
  return t;
}

void RoverSim::Impl::soil_terms(int i, double slip) {
  GroundContact& g = ground[i];
  const SoilTerms t = soil_terms_at(i, slip);
  st.slip[i] = t.slip;
  g.ax = t.ax;
  g.ay = t.ay;
  g.comp = t.comp;
  g.fz = t.fz;
  g.fz_pressure = t.fz_pressure;
  g.axle_torque = t.axle_torque;
}

// How far the soil terms of the step (at the slip it used) are from those at the slip eq 12
// gives at its end: the largest change of a row bound or explicit force [N], axle torques
// counted as forces at the wheel radius.
double RoverSim::Impl::soil_terms_gap(int i, double end_slip) {
  const GroundContact& g = ground[i];
  const SoilTerms t = soil_terms_at(i, end_slip);
  return std::max({std::abs(t.ax - g.ax), std::abs(t.ay - g.ay), std::abs(t.comp - g.comp),
                   std::abs(t.fz - g.fz), std::abs(t.axle_torque - g.axle_torque) / p.wheel_radius});
}

// The levels the soil rows of wheel i reached in the last solve (row_force, from settle()): the
// shear used as a fraction of its cap and the compaction force. The soil's terms that the rows do
// not produce (eq 32's shear part of the normal force, the axle torque) are evaluated at them.
void RoverSim::Impl::soil_levels(int i) {
  const GroundContact& g = ground[i];
  shear_x[i] = shear_y[i] = compaction[i] = 0.0;
  if (!g.active || opt.ground != GroundType::Soil) return;
  const double* f = &row_force[kRowsPerWheel * i];
  shear_x[i] = g.ax >= kMinRowBound ? clamp_unit(f[kShearX] / g.ax) : 0.0;
  shear_y[i] = g.ay >= kMinRowBound ? clamp_unit(f[kShearY] / g.ay) : 0.0;
  compaction[i] = f[kCompaction];
}

// Eq 12's inputs at the end of an attempt: the wheel centre's and the contact point's
// longitudinal velocities ODE reached, in the step's contact frame.
void RoverSim::Impl::end_velocity(int i, double& vx, double& vcx) const {
  const GroundContact& g = ground[i];
  const dBodyID wb = body[2 + i];
  const Vec3 v = to_vec(dBodyGetLinearVel(wb));
  const Vec3 vp = v + to_vec(dBodyGetAngularVel(wb)).cross(g.arm);
  vx = v.dot(g.fx);
  vcx = vp.dot(g.fx);
}

}  // namespace ernest::dynamics
