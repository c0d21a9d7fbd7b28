// ERNEST on ODE: rigid ground under the wheels (seed 004 §3.4: a linear spring–damper normal
// contact with Coulomb friction), its rows emitted for one attempt at a step and checked after
// it. rover_step.cpp explains the guessed active set; rover_rows.cpp has the other rows.
//
// Friction. Coulomb's law holds a constant force without motion. ODE's force-dependent slip
// (velocity = slip x force), used here before, is a viscous creep law instead: a rover parked on
// a hard 15 deg slope with mu 0.7 crept downhill at 0.5 cm/s without end. Each tyre now has a
// tangential spring–damper capped by Coulomb's law (per friction row, ODE's pyramid):
//   lambda = -k d - c v_t,  |lambda| <= mu F_n,
// v_t the tyre's slip velocity at the patch, d the spring's deflection: the slip accumulated while
// the row sticks (d' = v_t); while it slides, the deflection that carries the sliding force
// (d = -lambda / k), an elasto-plastic tyre. A constant force gives a constant deflection, not a
// constant speed; the compliance that lets wheels of slightly different rolling radii share a
// load instead of fighting stays. The deflection is a slip integral, not a point on the ground,
// so a rolling wheel (v_t = 0) keeps it. As a soft ODE row, implicit in the step h:
//   lambda = -k (d + h v_t) - c v_t:  motion = -(ERP / h) d, CFM = 1 / (h k + c), ERP = h k CFM.
//
// Rows of wheel i and their guesses: the normal row (pushing: the §3.4 spring–damper, bounded
// below by zero and solved exactly by the sparse solver; guessed at 0: no contact). Both friction
// rows inside mu F_n (sticking, the rolling wheel's usual case): unbounded spring–damper rows,
// checked after the step. Otherwise (sliding): ODE's friction rows bounded by mu times the
// contact's normal force (findex), which the solver hook (solver/ode_lcp.cpp) resolves with the
// final normal force (solve_coulomb), so the guessed and the bounded paths give the same Coulomb
// law.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "ernest/dynamics/rover_sim_impl.hpp"

namespace ernest::dynamics {

using namespace detail;

// Deflections at the start of the step: in the contact's tangent plane, zero off the ground.
void RoverSim::Impl::prepare_rigid() {
  for (int i = 0; i < 4; ++i) {
    const GroundContact& g = ground[i];
    Vec3& d = rigid_deflection[i];
    d = g.active ? Vec3(g.fx * d.dot(g.fx) + g.fy * d.dot(g.fy)) : Vec3(Vec3::Zero());
    rigid_deflection_end[i].setZero();
  }
}

// Whether wheel i's contact is emitted with its friction rows unbounded (guessed sticking).
bool RoverSim::Impl::rigid_sticking(RowModes modes, int i) const {
  return modes[kRowsPerWheel * i + kShearX] == RowState::Free &&
         modes[kRowsPerWheel * i + kShearY] == RowState::Free;
}

// The step's deflections become the next step's (after the accepted attempt).
void RoverSim::Impl::commit_rigid() { rigid_deflection = rigid_deflection_end; }

void RoverSim::Impl::emit_rigid(int i, RowModes modes) {
  const GroundContact& g = ground[i];
  if (modes[kRowsPerWheel * i + kNormal] == RowState::AtLo) return;  // guessed not pushing
  const bool sticking = rigid_sticking(modes, i);
  dContact ct;
  std::memset(&ct, 0, sizeof ct);
  for (int k = 0; k < 3; ++k) {
    ct.geom.pos[k] = g.point[k];
    ct.geom.normal[k] = g.n[k];
    ct.fdir1[k] = g.fx[k];  // then ODE's second friction row is n × x = y
  }
  ct.geom.depth = g.depth;
  ct.surface.mode = (sticking ? 0 : dContactApprox1) | dContactFDir1 | dContactSoftERP |
                    dContactSoftCFM | dContactSlip1 | dContactSlip2 | dContactMotion1 |
                    dContactMotion2;
  ct.surface.mu = sticking ? dInfinity : mu;
  ct.surface.soft_erp = contact_erp;
  ct.surface.soft_cfm = contact_cfm;
  ct.surface.slip1 = tangential_cfm[0];
  ct.surface.slip2 = tangential_cfm[1];
  ct.surface.motion1 = -tangential_erp[0] / h * rigid_deflection[i].dot(g.fx);
  ct.surface.motion2 = -tangential_erp[1] / h * rigid_deflection[i].dot(g.fy);
  add_contact_joint(ct, body[2 + i], nullptr, &ground_fb[i]);
}

// After the step: the contact's forces, where its laws put each row (next[]) and the deflection
// at the end of the step. Returns false if a guess was wrong: a missing contact that the spring
// would push, or a sticking contact whose normal force is not positive or whose friction exceeds
// mu times it. A bounded contact is right by construction (Coulomb's law, solve_coulomb).
bool RoverSim::Impl::settle_rigid(int i, RowModes modes, const Vec3& vp, RowStates& next) {
  const GroundContact& g = ground[i];
  const int r = kRowsPerWheel * i;
  if (modes[r + kNormal] == RowState::AtLo) {
    const double push = contact_erp * g.depth / h - vp.dot(g.n);
    next[r + kNormal] = push > 0.0 ? RowState::Free : RowState::AtLo;
    next[r + kShearX] = next[r + kShearY] = RowState::Free;
    rigid_deflection_end[i].setZero();  // no contact: the tyre relaxes
    return push <= 0.0;
  }
  const Vec3 f = to_vec(ground_fb[i].f1);
  const double fn = f.dot(g.n);
  row_force[r + kNormal] = fn;
  next[r + kNormal] = fn > 0.0 ? RowState::Free : RowState::AtLo;
  const double cap = mu * std::max(fn, 0.0);
  bool inside = true;
  Vec3 d_end = Vec3::Zero();
  for (int k = 0; k < 2; ++k) {
    const int row = r + (k == 0 ? kShearX : kShearY);
    const Vec3& dir = k == 0 ? g.fx : g.fy;
    const double d = rigid_deflection[i].dot(dir), v = vp.dot(dir);
    const double lambda = f.dot(dir);
    const double law = (-tangential_erp[k] / h * d - v) / tangential_cfm[k];  // unclamped force
    const RowState status = status_of(law, cap);
    row_force[row] = lambda;
    next[row] = status;
    inside = inside && std::abs(lambda) <= cap;
    // Sticking: the deflection grows by the step's slip; sliding: it carries the friction force.
    const double k_t = k == 0 ? opt.rigid_tyre_stiffness_x : opt.rigid_tyre_stiffness_y;
    d_end += dir * (status == RowState::Free ? d + h * v : k_t > 0.0 ? -lambda / k_t : 0.0);
  }
  rigid_deflection_end[i] = d_end;
  // The check is exact: |lambda| <= mu F_n, as Coulomb's law.
  return !rigid_sticking(modes, i) || (fn > 0.0 && inside);
}

}  // namespace ernest::dynamics

namespace ernest::dynamics {

using namespace detail;

// Obstacle contacts (seed 004 §3.4 against the boxes; near() in rover_step.cpp collects them),
// guessed like rigid ground: a wheel's points sticking (normal pushing, both friction rows inside
// mu F_n, ODE's pyramid) are emitted with unbounded friction rows, so that the step is one linear
// system for the sparse solver (solver/sparse_lcp.cpp) instead of ODE's pivoting with findex; a
// point of such a wheel found carrying no normal force is emitted without friction rows
// (obstacle_off); a wheel whose guess fails is emitted as before, ODE's contact with its friction
// bounded by mu times the normal force. modes: every row with its bounds (RowModes::all_bounded()):
// all bounded.
void RoverSim::Impl::emit_obstacles(RowModes modes) {
  for (int k = 0; k < n_obstacle_contacts; ++k) {
    const int w = obstacle_wheel[k];
    const bool sticking = modes.guessed() && w >= 0 && obstacle_try[w] == RowState::Free &&
                          opt.guess_obstacle_contacts;
    dContact c = obstacle_contact[k];
    if (sticking) {
      c.surface.mode &= ~dContactApprox1;
      c.surface.mu = (obstacle_off >> k & 1) ? 0.0 : dInfinity;
    }
    add_contact_joint(c, obstacle_bodies[2 * k], obstacle_bodies[2 * k + 1], &obstacle_fb[k]);
  }
}

// After the step: each wheel's next guess (obstacle_next: sticking where every loaded point's
// friction is strictly inside mu F_n: its force if it was guessed sticking, its slip velocity if
// it was bounded) and whether this attempt's sticking guesses held. A wrong
// guess is corrected for the next attempt: unloaded points lose their friction rows, and a wheel
// with a point beyond its friction cap, or an unloaded point that pushes, is bounded. Each
// correction adds an off point or a bounded wheel, so the attempts end.
bool RoverSim::Impl::settle_obstacles(RowModes modes) {
  std::array<bool, 4> inside{true, true, true, true}, bound_it{};
  std::uint64_t off = obstacle_off;
  for (int k = 0; k < n_obstacle_contacts; ++k) {
    const int w = obstacle_wheel[k];
    if (w < 0) continue;
    const dContact& c = obstacle_contact[k];
    const double side = obstacle_wheel_first[k] ? 1.0 : -1.0;  // force on the wheel
    const Vec3 f = side * to_vec(obstacle_wheel_first[k] ? obstacle_fb[k].f1 : obstacle_fb[k].f2);
    dVector3 t1, t2;
    dPlaneSpace(c.geom.normal, t1, t2);
    const double fn = side * f.dot(to_vec(c.geom.normal));
    const double cap = mu * std::max(fn, 0.0);
    const double l1 = std::abs(f.dot(to_vec(t1))), l2 = std::abs(f.dot(to_vec(t2)));
    const bool guessed =
        modes.guessed() && obstacle_try[w] == RowState::Free && opt.guess_obstacle_contacts;
    if (fn > 0.0 && guessed && !(l1 < cap && l2 < cap)) inside[w] = false;
    if (fn > 0.0 && !guessed) {
      // Bounded: sliding is read from the slip velocity (the row's law, lambda = -v_t / slip,
      // against mu F_n), not from the force: ODE's friction bound is mu times the normal force
      // of the moment it clamped, which can sit well below mu times the final one.
      dVector3 v;
      dBodyGetPointVel(body[2 + w], c.geom.pos[0], c.geom.pos[1], c.geom.pos[2], v);
      const double slip = c.surface.slip1;
      const double u1 = std::abs(to_vec(v).dot(to_vec(t1))), u2 = std::abs(to_vec(v).dot(to_vec(t2)));
      if (!(u1 < slip * cap && u2 < slip * cap)) inside[w] = false;
    }
    if (!guessed) continue;
    if (obstacle_off >> k & 1) {
      bound_it[w] = bound_it[w] || fn > 0.0;  // needs its friction after all
    } else if (!(fn > 0.0)) {
      off |= std::uint64_t{1} << k;
    } else if (!(l1 <= cap && l2 <= cap)) {
      bound_it[w] = true;
    }
  }
  bool held = off == obstacle_off;
  for (int w = 0; w < 4; ++w) {
    obstacle_next[w] = inside[w] ? RowState::Free : RowState::Bounded;
    if (bound_it[w]) {
      obstacle_try[w] = RowState::Bounded;
      held = false;
    }
  }
  obstacle_off = off;
  return held;
}

}  // namespace ernest::dynamics
