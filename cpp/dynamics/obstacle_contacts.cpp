// ERNEST on ODE: the obstacle contacts of a step (seed 004 §3.4: the rigid wheel–obstacle
// contact, a linear spring–damper with Coulomb friction) and the substeps of a step that touches
// an obstacle (SimOptions::obstacle_substeps). Collision (dSpaceCollide2 of the rover's space
// against the obstacles'), the contact's ODE surface parameters, the step length's ERP / CFM and
// the bodies saved and restored between the attempts of a step. The rows are emitted and checked
// in rover_rigid.cpp (emit_obstacles, settle_obstacles); the step itself is rover_step.cpp.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "ernest/dynamics/rover_sim_impl.hpp"

namespace ernest::dynamics {

using namespace detail;
void RoverSim::Impl::near(dGeomID a, dGeomID b) {
  dContact cs[kMaxContactsPerPair];
  std::memset(cs, 0, sizeof cs);
  const int n = dCollide(a, b, kMaxContactsPerPair, &cs[0].geom, sizeof(dContact));
  if (n <= 0) return;
  // The §3.4 stiffness is per wheel–obstacle contact: n simultaneous points share it, and so they
  // share the force-dependent slip (n points in parallel, each slipping at slip * n * its force,
  // slip at rigid_slip * total force). Per point, the contact's compliance would change with how
  // many points ODE's collider happens to return (4 or 6 for a wheel against a box edge, with
  // the step: benchmarks/RESULTS.md, "step independence").
  const double cfm = contact_cfm * n;
  const double slip = opt.rigid_slip * n;
  const dBodyID ba = dGeomGetBody(a), bb = dGeomGetBody(b);
  std::int8_t wheel = -1;
  bool first = true;
  for (int i = 0; i < 4; ++i) {
    if (ba == body[2 + i]) wheel = static_cast<std::int8_t>(i);
    if (bb == body[2 + i]) wheel = static_cast<std::int8_t>(i), first = false;
  }
  const dGeomID rock = first ? b : a;  // distinct obstacles touched (SolverStats)
  if (std::find(touched.begin(), touched.begin() + n_touched, rock) == touched.begin() + n_touched &&
      n_touched < static_cast<int>(touched.size()))
    touched[n_touched++] = rock;
  for (int k = 0; k < n && n_obstacle_contacts < kMaxObstacleContacts; ++k) {
    dContact& c = obstacle_contact[n_obstacle_contacts];
    c = cs[k];
    c.surface.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM | dContactSlip1 |
                     dContactSlip2;
    c.surface.slip1 = c.surface.slip2 = slip;
    c.surface.mu = mu;
    c.surface.soft_erp = contact_erp;
    c.surface.soft_cfm = cfm;
    obstacle_bodies[2 * n_obstacle_contacts] = ba;
    obstacle_bodies[2 * n_obstacle_contacts + 1] = bb;
    obstacle_wheel[n_obstacle_contacts] = wheel;
    obstacle_wheel_first[n_obstacle_contacts] = first;
    ++n_obstacle_contacts;
  }
}

void RoverSim::Impl::prepare_obstacles() {
  n_obstacle_contacts = 0;
  n_touched = 0;
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

// The §3.4 spring–dampers (obstacles, rigid ground, the tyre's tangential springs) as ODE's
// ERP / CFM for a step of the given length.
void RoverSim::Impl::set_step_length(double length) {
  h = length;
  contact_erp = opt.rigid.erp(h);
  contact_cfm = opt.rigid.cfm(h);
  for (int k = 0; k < 2; ++k) {  // the tyre's tangential spring–dampers as soft rows
    const double stiffness = k == 0 ? opt.rigid_tyre_stiffness_x : opt.rigid_tyre_stiffness_y;
    const double kh = stiffness * h + opt.rigid_tyre_damping;
    tangential_cfm[k] = 1.0 / kh;
    tangential_erp[k] = stiffness * h / kh;
  }
}

// Collects the step's obstacle contacts (at the current step length) and says whether there are
// any; step_once() then uses them instead of colliding again.
bool RoverSim::Impl::touching_obstacles() {
  if (obstacle_geoms.empty()) return false;
  prepare_obstacles();
  obstacles_collected = true;
  return n_obstacle_contacts > 0;
}

// One step of opt.dt; where a wheel touches an obstacle, opt.obstacle_substeps steps of
// opt.dt / n (SimOptions::obstacle_substeps: the contact is under-resolved at the default step).
// A force added with add_force() acts over the whole step.
void RoverSim::Impl::step() {
  init_ode_once();
  obstacles_collected = false;
  const int n = opt.obstacle_substeps;
  if (h != opt.dt) set_step_length(opt.dt);
  const bool touching = !diverged && touching_obstacles();
  stats.obstacles_touched = n_touched;
  if (n == 1 || !touching) {
    step_once();
    return;
  }
  // The contacts just collected are the first substep's (same poses): only their §3.4
  // compliance changes with the step length. A pair of m points has soft_cfm = m * contact_cfm
  // (near()); recover m and recompute as near() does, so that this is bit for bit a collision.
  const double full_cfm = contact_cfm;
  set_step_length(opt.dt / n);
  for (int k = 0; k < n_obstacle_contacts; ++k) {
    dSurfaceParameters& s = obstacle_contact[k].surface;
    s.soft_erp = contact_erp;
    s.soft_cfm = contact_cfm * static_cast<double>(std::lround(s.soft_cfm / full_cfm));
  }
  obstacles_collected = true;  // later substeps collide again (step_once)
  const Vec3 force = pending_force;
  for (int k = 0; k < n; ++k) {
    pending_force = force;
    step_once();
  }
}

}  // namespace ernest::dynamics
