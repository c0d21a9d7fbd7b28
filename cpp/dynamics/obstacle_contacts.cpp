// ERNEST on ODE: the obstacle contacts of a step (seed 004 §3.4: the rigid wheel–obstacle
// contact, a linear spring–damper with Coulomb friction) and the substeps of a step that touches
// an obstacle (SimOptions::obstacle_substeps). Collision (a broad phase per rover geom, exact
// early-outs for the wheels, then ODE's collider), one contact per rover-body–obstacle
// pair, its §3.4 rows' ERP / CFM (obstacle_contacts.hpp) and the bodies saved and restored
// between the attempts of a step. The rows are emitted and checked
// in rover_rigid.cpp (emit_obstacles, settle_obstacles); the step itself is rover_step.cpp.
#include "ernest/dynamics/obstacle_contacts.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "ernest/dynamics/cylinder_box.hpp"
#include "ernest/dynamics/rover_sim_impl.hpp"

namespace ernest::dynamics {

using namespace detail;

namespace detail {

dContactGeom merge_contact_points(const dContactGeom* points, int n) {
  dContactGeom m = points[0];
  double wsum = 0.0, deepest = 0.0;
  for (int k = 0; k < n; ++k) {
    wsum += std::max(points[k].depth, 0.0);
    deepest = std::max(deepest, points[k].depth);
  }
  Vec3 x = Vec3::Zero(), nrm = Vec3::Zero();
  for (int k = 0; k < n; ++k) {
    const double w = wsum > 0.0 ? std::max(points[k].depth, 0.0) / wsum : 1.0 / n;
    x += w * to_vec(points[k].pos);
    nrm += w * to_vec(points[k].normal);
  }
  // Opposite normals cancelling would leave no direction: keep the deepest point's then.
  const double len = nrm.norm();
  if (len > 1e-6) {
    nrm /= len;
  } else {
    int d = 0;
    for (int k = 1; k < n; ++k)
      if (points[k].depth > points[d].depth) d = k;
    nrm = to_vec(points[d].normal);
  }
  for (int i = 0; i < 3; ++i) m.normal[i] = nrm[i];
  for (int i = 0; i < 3; ++i) m.pos[i] = x[i];
  m.depth = deepest;
  return m;
}

// Seed 004 §3.4's spring k and damper c as a contact row (obstacle_contacts.hpp).
SpringDamperRow spring_damper_row(double k, double c, double h, double mass_bound) {
  SpringDamperRow r;
  const double omega_h = std::sqrt(k / mass_bound) * h;
  r.explicit_spring = c > 0.0 && omega_h <= kMaxExplicitOmegaH;  // NaN mass: implicit
  if (r.explicit_spring) {  // lambda = k depth(start) - c v_n'
    r.erp = h * k / c;
    r.cfm = 1.0 / c;
  } else {  // lambda = k depth(end) - c v_n': rigid ground's form
    soil::RigidContactParameters implicit_row;
    implicit_row.stiffness = k;
    implicit_row.damping = c;
    r.erp = implicit_row.erp(h);
    r.cfm = implicit_row.cfm(h);
  }
  return r;
}

bool cylinder_box_disjoint(const Vec3& c, const Vec3& u, double r, double hl, const Vec3& b,
                           const Mat3& rb, const Vec3& e) {
  const Vec3 q = rb.transpose() * (c - b), uq = rb.transpose() * u;  // box frame
  // reach of the cylinder along a unit axis n: r sqrt(1 - (n.u)^2) + hl |n.u|
  const auto reach = [&](double nu) {
    return r * std::sqrt(std::max(0.0, 1.0 - nu * nu)) + hl * std::abs(nu);
  };
  for (int i = 0; i < 3; ++i)  // the box's face normals
    if (std::abs(q[i]) > e[i] + reach(uq[i]) + kDisjointMargin) return true;
  const Vec3 d = q - q.cwiseMax(-e).cwiseMin(e);  // from the box's nearest point to c
  const double dist = d.norm();
  if (dist > kDisjointMargin && dist > reach(d.dot(uq) / dist) + kDisjointMargin) return true;
  // the cylinder's axis
  return std::abs(uq.dot(q)) > hl + e.dot(uq.cwiseAbs()) + kDisjointMargin;
}

// The exact contact (cylinder_box.hpp) as merge_contact_points(dCollide(cylinder, box)) gives
// it: the cylinder first, normal from the box into it, sides -1 (ODE's cylinder-box sets no side).
dContactGeom to_contact_geom(const CylinderBoxContact& c, dGeomID cylinder, dGeomID box) {
  dContactGeom g{};
  for (int i = 0; i < 3; ++i) {
    g.pos[i] = c.pos[i];
    g.normal[i] = c.normal[i];
  }
  g.depth = c.depth;
  g.g1 = cylinder;
  g.g2 = box;
  g.side1 = g.side2 = -1;
  return g;
}

}  // namespace detail

// A lower bound of the effective mass [kg] a contact row (at x along n) on rover body b sees:
// 1 / (j M^-1 j^T) with the step's constraints, bounded by dropping constraints (a constraint
// removes a positive semidefinite term from the row's inverse mass, the Schur complement of
// the rows J M^-1 J^T: without it the contact is lighter). A wheel: the wheel and its parent
// (bogie or chassis) held by the hinge (3 rows at its anchor, the wheel centre, and 2 against
// rotation off the axle), the spin free (its drive at its torque limit), the parent free in
// space. Another body, or with hinged false: itself, free (a lower bound again, cheaper).
// Fixed-size arithmetic: no allocation.
double RoverSim::Impl::contact_mass_bound(int b, const Vec3& x, const Vec3& n, bool hinged) const {
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  const auto inv_mass = [&](int i, Mat6& m) {  // [v; w] of body i, world frame
    dMass dm;
    dBodyGetMass(body[i], &dm);
    const Mat3 r = rot(i), in = to_mat(dm.I);
    m.setZero();
    m.topLeftCorner<3, 3>() = Mat3::Identity() / dm.mass;
    m.bottomRightCorner<3, 3>() = r * in.inverse() * r.transpose();
  };
  Mat6 mw;
  inv_mass(b, mw);
  Eigen::Matrix<double, 6, 1> j;
  j << n, (x - pos(b)).cross(n);
  if (b < 2 || !hinged) return 1.0 / j.dot(mw * j);
  const int parent = parent_of(b - 2);
  Mat6 mp;
  inv_mass(parent, mp);
  const Vec3 axle = axle_world(b - 2), rpw = pos(b) - pos(parent);
  Vec3 u1 = axle.unitOrthogonal(), u2 = axle.cross(u1);
  Eigen::Matrix<double, 6, 12> jac = Eigen::Matrix<double, 6, 12>::Zero();  // contact; hinge
  jac.block<1, 6>(0, 0) = j.transpose();
  for (int i = 0; i < 3; ++i) {  // v_w - (v_p + w_p x r_pw) = 0
    const Vec3 e = Vec3::Unit(i);
    jac.block<1, 3>(1 + i, 0) = e.transpose();
    jac.block<1, 3>(1 + i, 6) = -e.transpose();
    jac.block<1, 3>(1 + i, 9) = -rpw.cross(e).transpose();
  }
  jac.block<1, 3>(4, 3) = u1.transpose();
  jac.block<1, 3>(4, 9) = -u1.transpose();
  jac.block<1, 3>(5, 3) = u2.transpose();
  jac.block<1, 3>(5, 9) = -u2.transpose();
  // J M^-1 J^T with M^-1 block diagonal (lazy products: no general matrix-product kernel)
  const Eigen::Matrix<double, 6, 6> jw = jac.leftCols<6>(), jp = jac.rightCols<6>();
  const Mat6 a = jw.lazyProduct(mw).lazyProduct(jw.transpose()) +
                 jp.lazyProduct(mp).lazyProduct(jp.transpose());
  const Eigen::Matrix<double, 5, 1> ah = a.block<5, 1>(1, 0);
  const double s = a(0, 0) - ah.dot(a.bottomRightCorner<5, 5>().ldlt().solve(ah));
  return 1.0 / s;
}

// One contact per rover-body–obstacle pair from ODE's collider (merge_contact_points,
// obstacle_contacts.hpp).
void RoverSim::Impl::near(dGeomID a, dGeomID b) {
  dContactGeom points[kMaxContactsPerPair];
  const int n = dCollide(a, b, kMaxContactsPerPair, points, sizeof(dContactGeom));
  if (n > 0) add_obstacle_contact(a, b, merge_contact_points(points, n));
}

// A rover-body–obstacle pair's contact (merged: geoms and sides as its first point's), with the
// §3.4 spring–damper and Coulomb friction mu; its ERP / CFM are set by set_obstacle_rows().
void RoverSim::Impl::add_obstacle_contact(dGeomID a, dGeomID b, const dContactGeom& merged) {
  const dBodyID ba = dGeomGetBody(a), bb = dGeomGetBody(b);
  int rover = -1;
  bool first = true;
  for (int i = 0; i < 6; ++i) {
    if (ba == body[i]) rover = i;
    if (bb == body[i]) rover = i, first = false;
  }
  if (rover < 0) return;  // never: the obstacles' space holds no rover geom
  const dGeomID rock = first ? b : a;  // distinct obstacles touched (SolverStats)
  if (std::find(touched.begin(), touched.begin() + n_touched, rock) == touched.begin() + n_touched &&
      n_touched < static_cast<int>(touched.size()))
    touched[n_touched++] = rock;
  if (n_obstacle_contacts >= kMaxObstacleContacts) return;
  const int k = n_obstacle_contacts++;
  dContact& c = obstacle_contact[k];
  c = dContact{};
  c.geom = merged;
  // The force-dependent slip of the friction rows (SimOptions::rigid_slip), per contact.
  c.surface.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM | dContactSlip1 |
                   dContactSlip2;
  c.surface.slip1 = c.surface.slip2 = opt.rigid_slip;
  c.surface.mu = mu;
  obstacle_bodies[2 * k] = ba;
  obstacle_bodies[2 * k + 1] = bb;
  obstacle_body[k] = static_cast<std::int8_t>(rover);
  obstacle_wheel[k] = static_cast<std::int8_t>(rover >= 2 ? rover - 2 : -1);
  obstacle_wheel_first[k] = first;
  obstacle_hinged[k] = false;
  obstacle_mass[k] = contact_mass_bound(rover, to_vec(c.geom.pos), to_vec(c.geom.normal), false);
}

// The obstacle rows' ERP / CFM at the step length h (spring_damper_row, obstacle_contacts.hpp).
// Contacts on one assembly (the bogie with the front wheels, the chassis with the rear ones) are
// springs on bodies that move together (the front wheels see-sawing the bogie): the fastest mode
// of their springs has omega^2 = lambda_max(K A) <= trace(K A) = k sum_j A_jj, A the contacts'
// inverse-mass matrix (positive semidefinite), A_jj <= 1 / (contact j's mass bound). So the
// stability test takes, for every contact of an assembly, 1 / sum_j (1 / mass bound j). The two
// assemblies couple through the gimbal between heavy bodies (chassis 51 kg, bogie 12 kg): the
// margin of kMaxExplicitOmegaH below 2 is for that, and check_divergence() still reports a run
// that grows without bound.
void RoverSim::Impl::set_obstacle_rows() {
  const auto assembly = [](int b) { return b == kBogie || b == 2 || b == 3 ? 0 : 1; };
  const double k_spring = opt.rigid.stiffness;
  std::array<double, 2> inverse_mass{};
  const auto sum = [&] {
    inverse_mass = {};
    for (int k = 0; k < n_obstacle_contacts; ++k)
      inverse_mass[assembly(obstacle_body[k])] += 1.0 / obstacle_mass[k];
  };
  sum();
  // near() bounded each wheel's contact with the wheel alone; where that is too light for the
  // explicit spring, bound it again with the wheel's parent through the hinge (heavier, dearer).
  bool refined = false;
  for (int k = 0; k < n_obstacle_contacts; ++k) {
    const int b = obstacle_body[k];
    if (b < 2 || obstacle_hinged[k] ||
        std::sqrt(k_spring * inverse_mass[assembly(b)]) * h <= kMaxExplicitOmegaH)
      continue;
    const dContactGeom& g = obstacle_contact[k].geom;
    obstacle_mass[k] = contact_mass_bound(b, to_vec(g.pos), to_vec(g.normal), true);
    obstacle_hinged[k] = refined = true;
  }
  if (refined) sum();
  for (int k = 0; k < n_obstacle_contacts; ++k) {
    const SpringDamperRow r = spring_damper_row(k_spring, opt.rigid.damping, h,
                                                1.0 / inverse_mass[assembly(obstacle_body[k])]);
    dSurfaceParameters& s = obstacle_contact[k].surface;
    s.soft_erp = r.erp;
    s.soft_cfm = r.cfm;
    obstacle_explicit[k] = r.explicit_spring;
  }
}

void RoverSim::Impl::prepare_obstacles() {
  n_obstacle_contacts = 0;
  n_touched = 0;
  if (obstacle_geoms.empty()) return;
  const double wheel_radius = p.wheel_radius, wheel_half_width = 0.5 * p.wheel_width;
  // Broad phase: the rover's bounding box against each obstacle's (static: taken once by
  // build()), then each rover geom's box against it, and for a wheel the exact early-outs of
  // cylinder_box_disjoint(); ODE's collider (near()) only for what remains. dSpaceCollide2 of the
  // two simple spaces would test every rover geom against every obstacle (6 x 100 box tests a
  // call: 10 % of a step among 100 rocks); of the rover's space against each overlapping
  // obstacle, its boxes and call overhead would cost 2.5k instructions a step, and a quarter of
  // ODE's cylinder-box calls among 20 rocks find no contact. The geoms' boxes here are ODE's own formulas
  // (a box's, a cylinder's projection on each axis: exact) without cleaning ODE's space, and
  // kDisjointMargin wider: disjoint boxes prove disjoint shapes, where ODE finds no point.
  // The geoms are visited in a fixed order (chassis, bogie, wheels), the contacts in that order.
  std::array<std::array<double, 6>, 6> gbox;
  std::array<double, 6> box = {HUGE_VAL, -HUGE_VAL, HUGE_VAL, -HUGE_VAL, HUGE_VAL, -HUGE_VAL};
  std::array<Vec3, 6> centre;
  std::array<Mat3, 6> frame;
  for (int j = 0; j < 6; ++j) {
    centre[j] = to_vec(dGeomGetPosition(geom[j]));
    frame[j] = to_mat(dGeomGetRotation(geom[j]));
    Vec3 ext;
    if (j >= 2) {  // the cylinder's axis: its local z
      const Vec3 u = frame[j].col(2);
      ext = wheel_radius * (Vec3::Ones() - u.cwiseAbs2()).cwiseMax(0.0).cwiseSqrt() +
            wheel_half_width * u.cwiseAbs();
    } else {
      dVector3 lengths;
      dGeomBoxGetLengths(geom[j], lengths);
      ext = frame[j].cwiseAbs() * (0.5 * to_vec(lengths));
    }
    for (int i = 0; i < 3; ++i) {
      gbox[j][2 * i] = centre[j][i] - ext[i] - kDisjointMargin;
      gbox[j][2 * i + 1] = centre[j][i] + ext[i] + kDisjointMargin;
      box[2 * i] = std::min(box[2 * i], gbox[j][2 * i]);
      box[2 * i + 1] = std::max(box[2 * i + 1], gbox[j][2 * i + 1]);
    }
  }
  // The obstacles whose boxes may overlap the rover's along x: lowest x within the widest box's
  // width below the rover's box, found by bisection of the obstacles sorted by it; visited in
  // their own order (the order of the contacts), or all of them if there are too many.
  std::array<int, kMaxObstacleContacts> near_x;
  int n_near = 0;
  const auto by_x = [&](double x) {
    return std::lower_bound(obstacle_by_x.begin(), obstacle_by_x.end(), x,
                            [&](int k, double v) { return obstacle_aabb[k][0] < v; });
  };
  const auto first = by_x(box[0] - obstacle_max_width), last = by_x(box[1]);
  const bool all = last - first > static_cast<std::ptrdiff_t>(near_x.size());
  if (!all) {
    for (auto k = first; k != last; ++k) near_x[n_near++] = *k;
    std::sort(near_x.begin(), near_x.begin() + n_near);
  }
  const int n_visit = all ? static_cast<int>(obstacle_geoms.size()) : n_near;
  const bool exact = opt.wheel_obstacle_contact == WheelObstacleContact::Exact;
  for (int v = 0; v < n_visit; ++v) {
    const int i = all ? v : near_x[v];
    const std::array<double, 6>& ob = obstacle_aabb[i];
    const auto apart = [&](const std::array<double, 6>& b1) {
      return b1[0] > ob[1] || b1[1] < ob[0] || b1[2] > ob[3] || b1[3] < ob[2] || b1[4] > ob[5] ||
             b1[5] < ob[4];
    };
    if (apart(box)) continue;
    const dGeomID rock = obstacle_geoms[i];
    for (int j = 0; j < 6; ++j) {
      if (apart(gbox[j])) continue;
      if (j >= 2) {
        dVector3 lengths;
        dGeomBoxGetLengths(rock, lengths);
        const Vec3 rock_centre = to_vec(dGeomGetPosition(rock)), half = 0.5 * to_vec(lengths);
        const Mat3 rock_frame = to_mat(dGeomGetRotation(rock));
        if (exact) {  // the exact contact decides disjointness itself
          CylinderBoxContact cb;
          if (cylinder_box_contact(centre[j], frame[j].col(2), wheel_radius, wheel_half_width,
                                   rock_centre, rock_frame, half, cb))
            add_obstacle_contact(geom[j], rock, to_contact_geom(cb, geom[j], rock));
          continue;
        }
        if (cylinder_box_disjoint(centre[j], frame[j].col(2), wheel_radius, wheel_half_width,
                                  rock_centre, rock_frame, half))
          continue;
      }
      near(geom[j], rock);
    }
  }
  set_obstacle_rows();
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

// The §3.4 spring–dampers of rigid ground and the tyre's tangential springs as ODE's ERP / CFM
// for a step of the given length (the obstacles': set_obstacle_rows()).
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
// opt.dt / n, and with the default of one, more where a wheel's slip grew fast (below).
// A force added with add_force() acts over the whole step.
void RoverSim::Impl::step() {
  solver::init_ode_once();
  obstacles_collected = false;
  int n = opt.obstacle_substeps;
  if (h != opt.dt) set_step_length(opt.dt);
  const bool touching = !diverged && touching_obstacles();
  // With one substep, an obstacle step where a wheel's slip grew at a rate lambda in the last step
  // with dt lambda >= 1/2 is split into ceil(2 dt lambda) substeps (at most 8) so that each has
  // h lambda < 1/2. Near h lambda = 1 the implicit slip's amplification 1 / (1 - h lambda) turns
  // from growth to reversal and the step's equation in sigma has several roots, and neither it
  // nor the explicit slip (rover_step.cpp) follows a wheel that starts to surge up an obstacle's
  // face: the surge aborts, and a wheel left at v_x -> 0 with eq 12's slip ~ eps v_x^2 (no feedback)
  // stays there spinning (benchmarks/RESULTS.md, "Step size and step independence").
  constexpr double kMaxSplit = 8.0;  // at most 8 substeps
  if (n == 1 && touching && 2.0 * opt.dt * slip_rate >= 1.0)
    n = static_cast<int>(std::min(kMaxSplit, std::ceil(2.0 * opt.dt * slip_rate)));
  stats.obstacles_touched = n_touched;
  if (n == 1 || !touching) {
    step_once();
    return;
  }
  // The contacts just collected are the first substep's (same poses): only their §3.4 rows
  // change with the step length.
  set_step_length(opt.dt / n);
  set_obstacle_rows();
  obstacles_collected = true;  // later substeps collide again (step_once)
  const Vec3 force = pending_force;
  for (int k = 0; k < n; ++k) {
    pending_force = force;
    step_once();
  }
}

}  // namespace ernest::dynamics
