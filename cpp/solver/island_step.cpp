// Our own step of the rover's island: the step itself (island_step.hpp says why and when;
// island_rows.cpp: each joint's rows). Stage by stage as ODE 0.16.2's dxStepIsland
// (ode/src/step.cpp): 0, gravity and the implicit gyroscopic torque into the accumulators and the
// world-frame inverse inertias; 2a, the joints' rows (rhs and CFM over h); 2b/2c, A = J M⁻¹ Jᵀ +
// CFM and rhs = c / h - J (v / h + M⁻¹ f); 3, the solve (here solve_sparse, sparse_lcp.hpp); 4,
// the constraint forces Jᵀ lambda (and the joints' feedback), the velocity update and dxStepBody's
// integration (ode/src/util.cpp), written back with ODE's setters. resolve(): the same problem
// again with new targets and forces (island_resolve.cpp: its checks).
#include <algorithm>
#include <cmath>

#include "ernest/common/vector_math.hpp"
#include "ernest/solver/island_step.hpp"
#include "ernest/solver/ode_quaternion.hpp"

namespace ernest::solver {

// The step's parts, inlined into step() and resolve() (the step's path as one function, as before
// resolve() shared them).
#define ERNEST_INLINE __attribute__((always_inline)) inline

// Only our joints may act on our bodies (each permanent joint joins two of them), and the
// bodies must be plain dynamic ones: dxStepBody's options (finite rotation, speed cap, damping)
// and disabled or kinematic bodies are not reproduced. 42 calls into ODE (1.2 % of a step on
// flat ground when made every step): the answer is kept until bind(), add_*() or materialise()
// (the only calls that attach joints or come before the bodies are final; the world is
// RoverSim's alone, with auto-disable off, and nothing sets these options after build()).
bool IslandStep::bodies_supported() const {
  if (bodies_checked_) return true;
  int attached = 0;
  for (dBodyID b : body_) {
    if (!dBodyIsEnabled(b) || dBodyIsKinematic(b) || dBodyGetFiniteRotationMode(b) != 0 ||
        dBodyGetMaxAngularSpeed(b) != dInfinity || dBodyGetLinearDamping(b) != 0.0 ||
        dBodyGetAngularDamping(b) != 0.0)
      return false;
    attached += dBodyGetNumJoints(b);
  }
  bodies_checked_ = attached == 2 * n_permanent_;
  return bodies_checked_;
}

// Stage 0's accumulators: the force plus gravity, the torque plus the gyroscopic torque (gyro_,
// computed by step() from the body's state).
ERNEST_INLINE void IslandStep::load_forces(int i, const dVector3 gravity) {
  BodyState& s = bs_[i];
  const dBodyID b = body_[i];
  const dReal* f = dBodyGetForce(b);
  const dReal* t = dBodyGetTorque(b);
  for (int c = 0; c < 3; ++c) {
    s.facc_g[c] = f[c];
    s.tacc_g[c] = t[c];
    if (gravity[c] != 0.0 && dBodyGetGravityMode(b)) s.facc_g[c] += mass_[i] * gravity[c];
  }
  if (has_gyro_[i])
    for (int c = 0; c < 3; ++c) s.tacc_g[c] += gyro_[i][c];
}

// Stage 2b (and M⁻¹ Jᵀ of each row's sides with kWithJm): bx -= J (v / h + M⁻¹ f) per side.
template <bool kWithJm>
ERNEST_INLINE void IslandStep::form_rhs(int m, double fps) {
  std::array<std::array<double, 6>, kBodies> tmp1;
  for (int i = 0; i < kBodies; ++i) {
    const BodyState& s = bs_[i];
    for (int c = 0; c < 3; ++c) tmp1[i][c] = s.facc_g[c] * s.inv_mass + s.lvel[c] * fps;
    dMultiply0_331(&tmp1[i][3], s.invI, s.tacc_g);
    for (int c = 0; c < 3; ++c) tmp1[i][3 + c] += s.avel[c] * fps;
  }
  for (int r = 0; r < m; ++r) {
    const int sides[2] = {ra_[r], rb_[r]};
    for (int side = 0; side < 2; ++side) {
      const int bi = sides[side];
      if (bi < 0) continue;
      const double* J = &j_[r][6 * side];
      double sum = J[0] * tmp1[bi][0];
      for (int c = 1; c < 6; ++c) sum += J[c] * tmp1[bi][c];
      bx_[2 * r] -= sum;
      if (!kWithJm) continue;
      // M⁻¹ Jᵀ of this side: J_lin / m, invI J_ang (invI symmetric)
      double* JM = &jm_[r][6 * side];
      for (int c = 0; c < 3; ++c) JM[c] = J[c] * bs_[bi].inv_mass;
      dMultiply0_133(JM + 3, J + 3, bs_[bi].invI);
    }
  }
}

// Stage 3: the solve (kept_factor: resolve()'s, see solve_sparse).
ERNEST_INLINE bool IslandStep::solve(LcpWorkspace& ws, std::uint64_t kept_factor) {
  if (m_ == 0) return true;
  if (!solve_sparse(ws, static_cast<unsigned>(m_), a_.data(), bx_.data(), nullptr,
                    static_cast<unsigned>(kept_nub_), lh_.data(), findex_.data(), kept_factor))
    return false;
  ++ws.sparse;
  return true;
}

// Stage 4: constraint forces, feedback, velocities and poses.
ERNEST_INLINE void IslandStep::apply(double h) {
  for (auto& f : cforce_) f.fill(0.0);
  for (int k = 0; k < n_order_; ++k) {
    const Joint& jt = *order_[k];
    if (jt.rows == 0) continue;  // ODE drops joints without rows (their feedback stays)
    for (int side = 0; side < 2; ++side) {
      const int bi = side == 0 ? jt.row_a : jt.row_b;
      if (bi < 0) continue;
      double sum[6] = {0, 0, 0, 0, 0, 0};
      for (int r = jt.first; r < jt.first + jt.rows; ++r) {
        const double lambda = bx_[2 * r + 1];
        for (int c = 0; c < 6; ++c) sum[c] += j_[r][6 * side + c] * lambda;
      }
      if (jt.fb) {
        dReal* f = side == 0 ? jt.fb->f1 : jt.fb->f2;
        dReal* t = side == 0 ? jt.fb->t1 : jt.fb->t2;
        for (int c = 0; c < 3; ++c) {
          f[c] = sum[c];
          t[c] = sum[3 + c];
        }
      }
      for (int c = 0; c < 6; ++c) cforce_[bi][c] += sum[c];
    }
  }
  integrate(h);
}

IslandStep::Outcome IslandStep::step(dWorldID world, double h, LcpWorkspace& ws) {
  kept_ = false;
  if (!ws.enabled || n_attempt_ > kMaxAttemptJoints || !(h > 0.0)) return Outcome::Unsupported;
  if (!bodies_supported()) return Outcome::Unsupported;
  const double fps = 1.0 / h;  // ODE's dRecip(stepsize)
  const double erp = dWorldGetERP(world);
  world_cfm_ = dWorldGetCFM(world);
  min_depth_ = dWorldGetContactSurfaceLayer(world);
  max_vel_ = dWorldGetContactMaxCorrectingVel(world);
  dVector3 gravity;
  dWorldGetGravity(world, gravity);

  // ---- stage 0: accumulators with gravity and the gyroscopic torque; invI in the world frame
  for (int i = 0; i < kBodies; ++i) {
    BodyState& s = bs_[i];
    const dBodyID b = body_[i];
    s.pos = dBodyGetPosition(b);
    s.R = dBodyGetRotation(b);
    s.q = dBodyGetQuaternion(b);
    s.lvel = dBodyGetLinearVel(b);
    s.avel = dBodyGetAngularVel(b);
    s.inv_mass = 1.0 / mass_[i];
    double* kept = kept_state_[i].data();  // (resolve() compares the state it starts from)
    for (int c = 0; c < 3; ++c) {  // (element by element: std::copy calls memmove per range)
      kept[c] = s.pos[c];
      kept[19 + c] = s.lvel[c];
      kept[22 + c] = s.avel[c];
    }
    for (int c = 0; c < 4; ++c) kept[3 + c] = s.q[c];
    for (int c = 0; c < 12; ++c) kept[7 + c] = s.R[c];
    dMatrix3 tmp;
    dMultiply2_333(tmp, inv_inertia_body_[i].data(), s.R);
    dMultiply0_333(s.invI, s.R, tmp);
    has_gyro_[i] = false;
    if (dBodyGetGyroscopicMode(b)) {
      // Lacoursière's implicit gyroscopic torque, as stage 0: with I and L = I w in the world
      // frame, tau = (I (I - h [L]x)⁻¹ - 1) L / h
      dMatrix3 I, itild = {0}, itinv;
      dMultiply2_333(tmp, inertia_body_[i].data(), s.R);
      dMultiply0_333(I, s.R, tmp);
      dVector3 L;
      dMultiply0_331(L, I, s.avel);
      dSetCrossMatrixMinus(itild, L, 4);
      for (int k = 0; k < 12; ++k) itild[k] = itild[k] * h + I[k];
      dScaleVector3(L, fps);
      if (dInvertMatrix3(itinv, itild) != 0) {
        dMultiply0_333(itild, I, itinv);
        itild[0] -= 1;
        itild[5] -= 1;
        itild[10] -= 1;
        dVector3 tau0;
        dMultiply0_331(tau0, itild, L);
        for (int c = 0; c < 3; ++c) gyro_[i][c] = tau0[c];
        has_gyro_[i] = true;
      }
    }
    load_forces(i, gravity);
  }

  // ---- stage 2a: the rows, joints ordered as ODE's (purely unbounded joints first: nub rows)
  m_ = 0;
  n_order_ = 0;
  n_body_rows_.fill(0);
  int nub = 0;
  for (Kind kind : {Kind::Hinge, Kind::Universal, Kind::AMotor}) {
    for (int k = 0; k < n_permanent_; ++k) {
      Joint& jt = permanent_[k];
      if (jt.kind != kind) continue;
      if (!add_rows(jt, fps, erp)) return Outcome::Unsupported;
      if (kind == Kind::Hinge || (kind == Kind::Universal && jt.rows == 4 && nub == jt.first))
        nub = m_;
      order_[n_order_++] = &jt;
    }
  }
  n_permanent_order_ = n_order_;
  for (int k = 0; k < n_attempt_; ++k) {
    if (!add_rows(buffer(cur_)[k], fps, erp)) return Outcome::Unsupported;
    order_[n_order_++] = &buffer(cur_)[k];
  }
  const int m = m_;
  for (int r = 0; r < m; ++r) {
    // friction bounds tied to a normal force: only the sparse path's Coulomb guesses solve them
    if (findex_[r] >= 0 && !ws.coulomb_friction) return Outcome::Unsupported;
    c_[r] = bx_[2 * r];
    bx_[2 * r] *= fps;
    cfm_[r] *= fps;
  }

  // ---- stage 2b/2c: rhs = c / h - J (v / h + M⁻¹ f), and A
  form_rhs<true>(m, fps);
  build_a(m, h);
  kept_nub_ = nub;
  if (!solve(ws, 0)) return Outcome::SolveRefused;
  apply(h);
  // What resolve() needs to tell the same problem and to solve it again.
  kept_ = true;
  kept_buf_ = cur_;
  kept_n_attempt_ = n_attempt_;
  kept_factor_ = ws.factors;
  kept_h_ = h;
  kept_erp_ = erp;
  for (int c = 0; c < 3; ++c) kept_gravity_[c] = gravity[c];
  return Outcome::Stepped;
}

// The kept step's problem again with the new targets and forces: stage 0's accumulators, the
// rows' right-hand sides (the kept c / h but for the attempt's targets), stage 2b without
// M⁻¹ Jᵀ, the solve with the kept factor, stage 4. Each value is computed as step() computes it,
// from the same inputs: the same bits.
IslandStep::Outcome IslandStep::resolve(dWorldID world, double h, LcpWorkspace& ws) {
  const Match match = same_problem(world, h, ws);
  if (match == Match::Different) return step(world, h, ws);
  const double fps = 1.0 / h;
  const dVector3 gravity = {kept_gravity_[0], kept_gravity_[1], kept_gravity_[2], 0.0};
  for (int i = 0; i < kBodies; ++i) load_forces(i, gravity);
  for (int r = 0; r < m_; ++r) bx_[2 * r] = c_[r];
  const Joint* before = buffer(kept_buf_);
  for (int k = 0; k < n_attempt_; ++k) {
    Joint& jt = buffer(cur_)[k];
    const Joint& y = before[k];
    jt.first = y.first;
    jt.rows = y.rows;
    jt.row_a = y.row_a;
    jt.row_b = y.row_b;
    order_[n_permanent_order_ + k] = &jt;
    double c[3];
    const int n = std::min(attempt_targets(jt, fps, kept_erp_, c), jt.rows);
    for (int q = 0; q < n; ++q) bx_[2 * (jt.first + q)] = c_[jt.first + q] = c[q];
    if (match == Match::Caps) attempt_caps(jt, fps);
  }
  for (int r = 0; r < m_; ++r) bx_[2 * r] *= fps;
  form_rhs<false>(m_, fps);
  kept_ = false;
  if (!solve(ws, match == Match::Same ? kept_factor_ : 0)) return Outcome::SolveRefused;
  apply(h);
  kept_ = true;
  kept_buf_ = cur_;
  kept_factor_ = ws.factors;  // (a guess flipped in the solve factorised the same A again)
  return match == Match::Same ? Outcome::Resolved : Outcome::ResolvedCaps;
}

// A's lower triangle (row stride dPAD(m), ODE's layout for the solver), body by body: the rows
// touching body b (in row order), their Jacobians on b gathered column by column, so that row
// p's products with rows q <= p, (M⁻¹ Jᵀ)_p · J_q, are six independent multiply-adds per q that
// vectorise across q (entry by entry, each a chain of dependent adds, was as slow as ODE's).
// The diagonal starts at the row's CFM / h. Also compiled for AVX2 (common/vector_math.hpp: the
// same bits), 4 products a vector: -1 to -2 % of a step among rocks.
ERNEST_ALSO_AVX2
void IslandStep::build_a(int m, double h) {
  (void)h;
  if (m == 0) return;
  const int stride = dPAD(m);
  for (int r = 0; r < m; ++r) {  // (the solver reads row r up to column r + 1)
    double* row = &a_[static_cast<std::size_t>(r) * stride];
    std::fill(row, row + std::min(r + 2, stride), 0.0);
    row[r] = cfm_[r];
    n_diag_[r] = 0;
  }
  std::array<int, kMaxRows> rows;
  std::array<double, kMaxRows> dot;
  for (int b = 0; b < kBodies; ++b) {
    const int n = n_body_rows_[b];
    for (int k = 0; k < n; ++k) {
      const int r = body_rows_[b][k] >> 1, side = body_rows_[b][k] & 1;
      rows[k] = r;
      side_[k] = side;
      for (int c = 0; c < 6; ++c) jb_[c][k] = j_[r][6 * side + c];
    }
    for (int p = 0; p < n; ++p) {
      const double* jm = &jm_[rows[p]][6 * side_[p]];
      const double m0 = jm[0], m1 = jm[1], m2 = jm[2], m3 = jm[3], m4 = jm[4], m5 = jm[5];
      const double *j0 = jb_[0].data(), *j1 = jb_[1].data(), *j2 = jb_[2].data(),
                   *j3 = jb_[3].data(), *j4 = jb_[4].data(), *j5 = jb_[5].data();
      for (int q = 0; q <= p; ++q)
        dot[q] = ((m0 * j0[q] + m1 * j1[q]) + (m2 * j2[q] + m3 * j3[q])) + (m4 * j4[q] + m5 * j5[q]);
      double* arow = &a_[static_cast<std::size_t>(rows[p]) * stride];
      for (int q = 0; q <= p; ++q) arow[rows[q]] += dot[q];
      diag_[rows[p]][n_diag_[rows[p]]++] = dot[p];  // (resolve() adds them to a new CFM)
    }
  }
}

// Stage 4's velocity update and dxStepBody: v += h (f_c + f) / m, w += invI h (t_c + t), then
// x += h v and q += h dq(w, q), normalised and turned into R by dBodySetQuaternion (ODE's own
// dNormalize4 and dQtoR, as dxStepBody); the accumulators are cleared.
void IslandStep::integrate(double h) {
  quaternions_fixed_ = true;
  for (int i = 0; i < kBodies; ++i) {
    const BodyState& s = bs_[i];
    const dBodyID b = body_[i];
    const double hm = h * s.inv_mass;
    dVector3 v, w, acc;
    for (int c = 0; c < 3; ++c) {
      v[c] = s.lvel[c] + (cforce_[i][c] + s.facc_g[c]) * hm;
      acc[c] = (cforce_[i][3 + c] + s.tacc_g[c]) * h;
      w[c] = s.avel[c];
    }
    dMultiplyAdd0_331(w, s.invI, acc);
    dReal pos[3], dq[4], q[4];
    for (int c = 0; c < 3; ++c) pos[c] = s.pos[c] + h * v[c];
    dDQfromW(dq, w, s.q);
    for (int c = 0; c < 4; ++c) q[c] = s.q[c] + h * dq[c];
    dBodySetLinearVel(b, v[0], v[1], v[2]);
    dBodySetAngularVel(b, w[0], w[1], w[2]);
    dBodySetPosition(b, pos[0], pos[1], pos[2]);
    // Where it can, the quaternion RoverSim's read_outputs() would canonicalise it to, so that
    // ODE is called once (ode_quaternion.hpp): the same bits as setting q and canonicalising.
    dQuaternion fixed;
    const bool found = fixed_point_quaternion(q, fixed);
    quaternions_fixed_ = quaternions_fixed_ && found;
    dBodySetQuaternion(b, found ? fixed : q);
    dBodySetForce(b, 0, 0, 0);
    dBodySetTorque(b, 0, 0, 0);
  }
}

#undef ERNEST_INLINE

}  // namespace ernest::solver
