// Our own step of the rover's island: each joint's rows (island_step.hpp says why and when;
// island_step.cpp: the step itself). The facts are ODE
// 0.16.2's: ode/src/step.cpp (dxStepIsland: stages 0 to 4), ode/src/util.cpp (dxStepBody), and
// each joint's getInfo1/getInfo2 (joints/hinge.cpp, universal.cpp, amotor.cpp, lmotor.cpp,
// contact.cpp; setBall and dxJointLimitMotor::addLimot in joints/joint.cpp). ODE's public inline
// helpers (odemath.h, rotation.h) do the small products so that the arithmetic is ODE's own.
#include "ernest/solver/island_step.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace ernest::solver {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ODE's rotational stop test (joint.cpp, testRotationalLimit): 1 low, 2 high, 0 none.
int rotational_limit(double angle, double lo, double hi, double& err) {
  if (angle <= lo) {
    err = angle - lo;
    return 1;
  }
  if (angle >= hi) {
    err = angle - hi;
    return 2;
  }
  return 0;
}

}  // namespace

void IslandStep::bind(const std::array<dBodyID, kBodies>& bodies) {
  body_ = bodies;
  for (int i = 0; i < kBodies; ++i) {
    dMass m;
    dBodyGetMass(body_[i], &m);
    mass_[i] = m.mass;
    std::copy(m.I, m.I + 12, inertia_body_[i].begin());
    // ODE's invI (dBodySetMass: dInvertPDMatrix of the 3x3 inertia)
    dReal inv[12]{};
    dInvertMatrix3(inv, m.I);
    std::copy(inv, inv + 12, inv_inertia_body_[i].begin());
  }
  n_permanent_ = 0;
  n_attempt_ = 0;
  kept_ = false;
  bodies_checked_ = false;
}

int IslandStep::body_index(dBodyID b) const {
  if (b == nullptr) return -1;
  for (int i = 0; i < kBodies; ++i)
    if (body_[i] == b) return i;
  return -2;  // not ours
}

IslandStep::Joint& IslandStep::add_permanent(dJointID j, Kind kind) {
  if (n_permanent_ >= static_cast<int>(permanent_.size()))
    throw std::length_error("IslandStep: more permanent joints than it holds");
  Joint& jt = permanent_[n_permanent_++];
  bodies_checked_ = false;
  jt = Joint{};
  jt.kind = kind;
  jt.id = j;
  jt.a = body_index(dJointGetBody(j, 0));
  jt.b = body_index(dJointGetBody(j, 1));
  jt.fb = dJointGetFeedback(j);
  return jt;
}

void IslandStep::add_hinge(dJointID j, const dReal axis_world[3]) {
  Joint& jt = add_permanent(j, Kind::Hinge);
  // its stops and motor (hinge_rows refuses either; never set after build)
  hinge_params_[n_permanent_ - 1] = HingeParams{dJointGetHingeParam(j, dParamLoStop),
                                                dJointGetHingeParam(j, dParamHiStop),
                                                dJointGetHingeParam(j, dParamFMax)};
  // setAxes (joint.cpp): the normalised axis in body 2's frame, R2ᵀ q
  dReal q[4] = {axis_world[0], axis_world[1], axis_world[2], 0.0};
  dNormalize3(q);
  dMultiply1_331(jt.axis2, dBodyGetRotation(dJointGetBody(j, 1)), q);
}

void IslandStep::add_universal(dJointID j) { add_permanent(j, Kind::Universal); }

void IslandStep::add_amotor(dJointID j) {
  add_permanent(j, Kind::AMotor);
  MotorParams& m = motor_params_[n_permanent_ - 1];
  m.mode = dJointGetAMotorMode(j);
  m.num_axes = dJointGetAMotorNumAxes(j);
  for (int i = 0; i < 3; ++i) {
    const int g = i * (dParamGroup2 - dParamGroup1);
    m.lo[i] = dJointGetAMotorParam(j, dParamLoStop + g);
    m.hi[i] = dJointGetAMotorParam(j, dParamHiStop + g);
    m.fmax[i] = dJointGetAMotorParam(j, dParamFMax + g);
    m.vel[i] = dJointGetAMotorParam(j, dParamVel + g);
    m.cfm[i] = dJointGetAMotorParam(j, dParamCFM + g);
  }
}

void IslandStep::set_amotor_param(dJointID j, int parameter, double value) {
  dJointSetAMotorParam(j, parameter, value);
  forget();
  int k = 0;
  while (k < n_permanent_ && permanent_[k].id != j) ++k;
  if (k == n_permanent_ || permanent_[k].kind != Kind::AMotor)
    throw std::invalid_argument("IslandStep::set_amotor_param: not one of its angular motors");
  MotorParams& m = motor_params_[k];
  const int group = (parameter - dParamLoStop) / (dParamGroup2 - dParamGroup1);
  if (group < 0 || group > 2) throw std::invalid_argument("IslandStep::set_amotor_param: parameter");
  const int base = parameter - group * (dParamGroup2 - dParamGroup1);
  std::array<double, 3>* slot = base == dParamLoStop ? &m.lo
                                : base == dParamHiStop ? &m.hi
                                : base == dParamFMax ? &m.fmax
                                : base == dParamVel ? &m.vel
                                : base == dParamCFM ? &m.cfm : nullptr;
  // (a parameter step() does not read: ODE has it, the copy needs nothing)
  if (slot) (*slot)[group] = dJointGetAMotorParam(j, parameter);  // as ODE stored it
}

void IslandStep::add_contact(const dContact& c, dBodyID b1, dBodyID b2, dJointFeedback* fb) {
  if (n_attempt_ >= kMaxAttemptJoints) {  // counted, not kept: step() refuses (never: the caller's static_assert)
    ++n_attempt_;
    return;
  }
  Joint& jt = buffer(cur_)[n_attempt_++];
  jt.kind = Kind::Contact;
  jt.contact = c;
  jt.a = body_index(b1);
  jt.b = body_index(b2);
  jt.fb = fb;
}

void IslandStep::add_lmotor(dBodyID b, const double axis[3], double vel, double fmax, double cfm) {
  if (n_attempt_ >= kMaxAttemptJoints) {
    ++n_attempt_;
    return;
  }
  Joint& jt = buffer(cur_)[n_attempt_++];
  jt.kind = Kind::LMotor;
  jt.a = body_index(b);
  jt.b = -1;
  jt.fb = nullptr;
  std::copy(axis, axis + 3, jt.lm_axis);
  jt.lm_vel = vel;
  jt.lm_fmax = fmax;
  jt.lm_cfm = cfm;
}

void IslandStep::materialise(dWorldID world, dJointGroupID group) const {
  bodies_checked_ = false;  // joints attached to the bodies (until the group is emptied)
  const int n = std::min(n_attempt_, kMaxAttemptJoints);
  for (int k = 0; k < n; ++k) {
    const Joint& jt = buffer(cur_)[k];
    const dBodyID a = jt.a >= 0 ? body_[jt.a] : nullptr, b = jt.b >= 0 ? body_[jt.b] : nullptr;
    if (jt.kind == Kind::Contact) {
      dJointID j = dJointCreateContact(world, group, &jt.contact);
      dJointAttach(j, a, b);
      if (jt.fb) dJointSetFeedback(j, jt.fb);
    } else {
      dJointID j = dJointCreateLMotor(world, group);
      dJointAttach(j, a, nullptr);
      dJointSetLMotorNumAxes(j, 1);
      dJointSetLMotorAxis(j, 0, 0, jt.lm_axis[0], jt.lm_axis[1], jt.lm_axis[2]);
      dJointSetLMotorParam(j, dParamVel, jt.lm_vel);
      dJointSetLMotorParam(j, dParamFMax, jt.lm_fmax);
      dJointSetLMotorParam(j, dParamCFM, jt.lm_cfm);
    }
  }
}

// setBall (joint.cpp): three rows holding the anchors together, J1 = [I, -[a1]x],
// J2 = [-I, [a2]x], rhs = erp fps (anchor2 - anchor1).
bool IslandStep::ball_rows(Joint& jt, const dReal* w1, const dReal* w2, double k) {
  double* J[3];
  double* rhs[3];
  for (int i = 0; i < 3; ++i) {
    const int r = new_row(jt, world_cfm_);
    if (r < 0) return false;
    J[i] = j_[r].data();
    rhs[i] = &bx_[2 * r];
  }
  const dReal *p1 = bs_[jt.a].pos, *p2 = bs_[jt.b].pos;
  const double a1[3] = {w1[0] - p1[0], w1[1] - p1[1], w1[2] - p1[2]};
  const double a2[3] = {w2[0] - p2[0], w2[1] - p2[1], w2[2] - p2[2]};
  for (int i = 0; i < 3; ++i) {
    double* j = J[i];
    j[i] = 1.0;
    // row i of -[a1]x is a1 x e_i; of [a2]x, -(a2 x e_i)
    const int u = (i + 1) % 3, v = (i + 2) % 3;
    j[3 + u] = a1[v];
    j[3 + v] = -a1[u];
    j[6 + i] = -1.0;
    j[9 + u] = -a2[v];
    j[9 + v] = a2[u];
    *rhs[i] = k * (w2[i] - w1[i]);
  }
  return true;
}

// A row against rotation about d of body a relative to body b: J = [0, d; 0, -d]. -1: too many.
int IslandStep::angular_row(Joint& jt, const dReal* d) {
  const int r = new_row(jt, world_cfm_);
  if (r < 0) return -1;
  for (int c = 0; c < 3; ++c) {
    j_[r][3 + c] = d[c];
    j_[r][9 + c] = -d[c];
  }
  return r;
}

bool IslandStep::hinge_rows(Joint& jt, double fps, double erp) {
  const dJointID j = jt.id;
  // A motor or stops on the hinge itself add a row this step does not reproduce.
  const HingeParams& hp = hinge_params_[&jt - permanent_.data()];
  const double lo = hp.lo, hi = hp.hi;
  if (hp.fmax > 0.0 || ((lo >= -M_PI || hi <= M_PI) && lo <= hi)) return false;
  if (jt.a < 0 || jt.b < 0) return false;
  dVector3 w1, w2, ax1, ax2, p, q, b;
  dJointGetHingeAnchor(j, w1);
  dJointGetHingeAnchor2(j, w2);
  const double k = fps * erp;
  if (!ball_rows(jt, w1, w2, k)) return false;
  // hinge.cpp: two rows against rotation off the axis, p and q spanning its normal plane
  dJointGetHingeAxis(j, ax1);
  dPlaneSpace(ax1, p, q);
  dMultiply0_331(ax2, bs_[jt.b].R, jt.axis2);
  dCalcVectorCross3(b, ax1, ax2);
  const dReal* dirs[2] = {p, q};
  for (const dReal* d : dirs) {
    const int r = angular_row(jt, d);
    if (r < 0) return false;
    bx_[2 * r] = k * dCalcVectorDot3(b, d);
  }
  return true;
}

bool IslandStep::universal_rows(Joint& jt, double fps, double erp) {
  const dJointID j = jt.id;
  if (jt.a < 0 || jt.b < 0) return false;
  dVector3 w1, w2, ax1, ax2, ax2t, p;
  dJointGetUniversalAnchor(j, w1);
  dJointGetUniversalAnchor2(j, w2);
  const double k = fps * erp;
  if (!ball_rows(jt, w1, w2, k)) return false;
  // universal.cpp: one row against rotation about the normal of both axes
  dJointGetUniversalAxis1(j, ax1);
  dJointGetUniversalAxis2(j, ax2);
  const double dot = dCalcVectorDot3(ax1, ax2);
  dAddVectorScaledVector3(ax2t, ax2, ax1, -dot);
  dCalcVectorCross3(p, ax1, ax2t);
  dNormalize3(p);
  int r = angular_row(jt, p);
  if (r < 0) return false;
  bx_[2 * r] = fps * erp * (-dot);
  // the stops (addLimot with limit set; no motor on the joint itself)
  const int lo_p[2] = {dParamLoStop, dParamLoStop2}, hi_p[2] = {dParamHiStop, dParamHiStop2};
  const int base[2] = {0, dParamGroup2 - dParamGroup1};
  double lo[2], hi[2];
  bool limiting[2];
  for (int s = 0; s < 2; ++s) {
    if (dJointGetUniversalParam(j, dParamFMax + base[s]) > 0.0) return false;
    lo[s] = dJointGetUniversalParam(j, lo_p[s]);
    hi[s] = dJointGetUniversalParam(j, hi_p[s]);
    limiting[s] = (lo[s] >= -M_PI || hi[s] <= M_PI) && lo[s] <= hi[s];
  }
  if (!limiting[0] && !limiting[1]) return true;
  double angle[2];
  dJointGetUniversalAngles(j, &angle[0], &angle[1]);
  for (int s = 0; s < 2; ++s) {
    double err = 0.0;
    const int limit = limiting[s] ? rotational_limit(angle[s], lo[s], hi[s], err) : 0;
    if (limit == 0) continue;
    if (dJointGetUniversalParam(j, dParamBounce + base[s]) > 0.0) return false;
    r = angular_row(jt, s == 0 ? ax1 : ax2);
    if (r < 0) return false;
    bx_[2 * r] = -fps * dJointGetUniversalParam(j, dParamStopERP + base[s]) * err;
    cfm_[r] = dJointGetUniversalParam(j, dParamStopCFM + base[s]);
    if (lo[s] != hi[s]) {
      lh_[2 * r] = limit == 1 ? 0.0 : -kInf;
      lh_[2 * r + 1] = limit == 1 ? kInf : 0.0;
    }
  }
  return true;
}

bool IslandStep::amotor_rows(Joint& jt) {
  const dJointID j = jt.id;
  const MotorParams& mp = motor_params_[&jt - permanent_.data()];
  if (mp.mode != dAMotorUser || jt.a < 0) return false;
  const int num = mp.num_axes;
  for (int i = 0; i < num; ++i) {
    double err = 0.0;
    if ((mp.lo[i] != -dInfinity || mp.hi[i] != dInfinity) &&
        rotational_limit(dJointGetAMotorAngle(j, i), mp.lo[i], mp.hi[i], err) != 0)
      return false;  // a stop on the motor: not reproduced
    const double fmax = mp.fmax[i];
    if (!(fmax > 0.0)) continue;
    dVector3 ax;
    dJointGetAMotorAxis(j, i, ax);
    const int r = new_row(jt, world_cfm_);
    if (r < 0) return false;
    for (int c = 0; c < 3; ++c) {
      j_[r][3 + c] = ax[c];
      if (jt.b >= 0) j_[r][9 + c] = -ax[c];
    }
    bx_[2 * r] = mp.vel[i];
    cfm_[r] = mp.cfm[i];
    lh_[2 * r] = -fmax;
    lh_[2 * r + 1] = fmax;
  }
  return true;
}

bool IslandStep::lmotor_rows(Joint& jt) {
  if (jt.a < 0 || !(jt.lm_fmax > 0.0)) return jt.a >= 0;
  const int r = new_row(jt, world_cfm_);
  if (r < 0) return false;
  for (int c = 0; c < 3; ++c) j_[r][c] = jt.lm_axis[c];  // one body: no torque decoupling
  attempt_targets(jt, 0.0, 0.0, &bx_[2 * r]);  // lm_vel
  cfm_[r] = jt.lm_cfm;
  lh_[2 * r] = -jt.lm_fmax;
  lh_[2 * r + 1] = jt.lm_fmax;
  return true;
}

bool IslandStep::contact_rows(Joint& jt, double fps, double erp) {
  const dContact& ct = jt.contact;
  const dSurfaceParameters& s = ct.surface;
  constexpr int kUnsupported = dContactBounce | dContactRolling;
  if (s.mode & kUnsupported) return false;
  if (jt.a == -2 || jt.b == -2) return false;
  dVector3 normal = {ct.geom.normal[0], ct.geom.normal[1], ct.geom.normal[2], 0.0};
  if (jt.a < 0) {  // dJointAttach(0, b): ODE makes b the first body and flips the normal
    if (jt.b < 0) return true;  // attached to nothing: no rows
    jt.row_a = jt.b;
    jt.row_b = -1;
    for (int c = 0; c < 3; ++c) normal[c] = -normal[c];
  }
  // getInfo1: a negative mu counts as 0. With dContactMu2 (= dContactAxisDep in 0.16) each
  // direction has its own row where its mu > 0; without, mu > 0 gives both (mu2 = mu).
  const double mu1 = s.mu < 0.0 ? 0.0 : s.mu;
  const double mu2 = (s.mode & dContactAxisDep) ? (s.mu2 < 0.0 ? 0.0 : s.mu2) : mu1;
  const bool two = jt.row_b >= 0;
  dVector3 c1, c2 = {0, 0, 0, 0};
  const BodyState& b0 = bs_[jt.row_a];
  for (int c = 0; c < 3; ++c) c1[c] = ct.geom.pos[c] - b0.pos[c];
  if (two)
    for (int c = 0; c < 3; ++c) c2[c] = ct.geom.pos[c] - bs_[jt.row_b].pos[c];
  double target[3];  // the rows' right-hand sides
  attempt_targets(jt, fps, erp, target);
  const int first = m_;
  int r = new_row(jt, world_cfm_);
  if (r < 0) return false;
  // J1 = [n, c1 x n], J2 = [-n, n x c2]
  for (int c = 0; c < 3; ++c) j_[r][c] = normal[c];
  dCalcVectorCross3(&j_[r][3], c1, normal);
  if (two) {
    for (int c = 0; c < 3; ++c) j_[r][6 + c] = -normal[c];
    dCalcVectorCross3(&j_[r][9], normal, c2);
  }
  bx_[2 * r] = target[0];
  if (s.mode & dContactSoftCFM) cfm_[r] = s.soft_cfm;
  lh_[2 * r] = 0.0;
  lh_[2 * r + 1] = kInf;
  if (!(mu1 > 0.0) && !(mu2 > 0.0)) return true;
  dVector3 t[2];
  if (s.mode & dContactFDir1) {
    for (int c = 0; c < 3; ++c) t[0][c] = ct.fdir1[c];
    dCalcVectorCross3(t[1], normal, t[0]);
  } else {
    dPlaneSpace(normal, t[0], t[1]);
  }
  const double mu[2] = {mu1, mu2};
  const int slip[2] = {dContactSlip1, dContactSlip2};
  const int approx[2] = {dContactApprox1_1, dContactApprox1_2};
  const double sval[2] = {s.slip1, s.slip2};
  int next_target = 1;
  for (int d = 0; d < 2; ++d) {
    if (!(mu[d] > 0.0)) continue;
    r = new_row(jt, world_cfm_);
    if (r < 0) return false;
    for (int c = 0; c < 3; ++c) j_[r][c] = t[d][c];
    dCalcVectorCross3(&j_[r][3], c1, t[d]);
    if (two) {
      for (int c = 0; c < 3; ++c) j_[r][6 + c] = -t[d][c];
      dCalcVectorCross3(&j_[r][9], t[d], c2);
    }
    bx_[2 * r] = target[next_target++];
    if (s.mode & slip[d]) cfm_[r] = sval[d];
    lh_[2 * r] = -mu[d];
    lh_[2 * r + 1] = mu[d];
    if (s.mode & approx[d]) findex_[r] = first;
  }
  return true;
}

// The right-hand sides (before stage 2a's 1 / h) of an attempt joint's rows, in row order: a
// contact's normal row (fps erp depth + motionN, capped by the world's correcting velocity) and
// its friction rows (their motion), a linear motor's speed. All that differs between a step and
// its resolve() (island_step.hpp); contact_rows and lmotor_rows take them from here.
int IslandStep::attempt_targets(const Joint& jt, double fps, double erp, double* c) const {
  if (jt.kind == Kind::LMotor) {
    if (jt.a < 0 || !(jt.lm_fmax > 0.0)) return 0;
    c[0] = jt.lm_vel;
    return 1;
  }
  const dSurfaceParameters& s = jt.contact.surface;
  const double e = (s.mode & dContactSoftERP) ? s.soft_erp : erp;
  double depth = jt.contact.geom.depth - min_depth_;
  if (depth < 0.0) depth = 0.0;
  const double motion_n = (s.mode & dContactMotionN) ? s.motionN : 0.0;
  const double pushout = fps * e * depth + motion_n;
  c[0] = pushout > max_vel_ ? max_vel_ : pushout;
  int n = 1;
  const double mu1 = s.mu < 0.0 ? 0.0 : s.mu;
  const double mu2 = (s.mode & dContactAxisDep) ? (s.mu2 < 0.0 ? 0.0 : s.mu2) : mu1;
  if (mu1 > 0.0) c[n++] = (s.mode & dContactMotion1) ? s.motion1 : 0.0;
  if (mu2 > 0.0) c[n++] = (s.mode & dContactMotion2) ? s.motion2 : 0.0;
  return n;
}

bool IslandStep::add_rows(Joint& jt, double fps, double erp) {
  jt.first = m_;
  jt.rows = 0;
  jt.row_a = jt.a;
  jt.row_b = jt.b;
  if (jt.id != nullptr && !dJointIsEnabled(jt.id)) return false;  // (ODE leaves it out)
  switch (jt.kind) {
    case Kind::Hinge: return hinge_rows(jt, fps, erp);
    case Kind::Universal: return universal_rows(jt, fps, erp);
    case Kind::AMotor: return amotor_rows(jt);
    case Kind::Contact: return contact_rows(jt, fps, erp);
    case Kind::LMotor: return lmotor_rows(jt);
  }
  return false;
}

}  // namespace ernest::solver
