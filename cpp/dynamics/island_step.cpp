// Our own step of the rover's island: the step itself (island_step.hpp says why and when;
// island_rows.cpp: each joint's rows). Stage by stage as ODE 0.16.2's dxStepIsland
// (ode/src/step.cpp): 0, gravity and the implicit gyroscopic torque into the accumulators and the
// world-frame inverse inertias; 2a, the joints' rows (rhs and CFM over h); 2b/2c, A = J M⁻¹ Jᵀ +
// CFM and rhs = c / h - J (v / h + M⁻¹ f); 3, the solve (here solve_sparse, ode_lcp.hpp); 4, the
// constraint forces Jᵀ lambda (and the joints' feedback), the velocity update and dxStepBody's
// integration (ode/src/util.cpp), written back with ODE's setters.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "ernest/dynamics/island_step.hpp"

namespace ernest::dynamics::detail {

IslandStep::Outcome IslandStep::step(dWorldID world, double h, LcpWorkspace& ws) {
  if (!ws.enabled || n_attempt_ > kMaxAttemptJoints || !(h > 0.0)) return Outcome::Unsupported;
  // Only our joints may act on our bodies (each permanent joint joins two of them), and the
  // bodies must be plain dynamic ones: dxStepBody's options (finite rotation, speed cap,
  // damping) and disabled or kinematic bodies are not reproduced.
  int attached = 0;
  for (dBodyID b : body_) {
    if (!dBodyIsEnabled(b) || dBodyIsKinematic(b) || dBodyGetFiniteRotationMode(b) != 0 ||
        dBodyGetMaxAngularSpeed(b) != dInfinity || dBodyGetLinearDamping(b) != 0.0 ||
        dBodyGetAngularDamping(b) != 0.0)
      return Outcome::Unsupported;
    attached += dBodyGetNumJoints(b);
  }
  if (attached != 2 * n_permanent_) return Outcome::Unsupported;
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
    const dReal* f = dBodyGetForce(b);
    const dReal* t = dBodyGetTorque(b);
    s.inv_mass = 1.0 / mass_[i];
    for (int c = 0; c < 3; ++c) {
      s.facc_g[c] = f[c];
      s.tacc_g[c] = t[c];
      if (gravity[c] != 0.0 && dBodyGetGravityMode(b)) s.facc_g[c] += mass_[i] * gravity[c];
    }
    stage0(i, h);
  }

  // ---- stage 2a: the rows, joints ordered as ODE's (purely unbounded joints first: nub rows)
  m_ = 0;
  n_order_ = 0;
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
  for (int k = 0; k < n_attempt_; ++k) {
    if (!add_rows(attempt_[k], fps, erp)) return Outcome::Unsupported;
    order_[n_order_++] = &attempt_[k];
  }
  const int m = m_;
  for (int r = 0; r < m; ++r) {
    // friction bounds tied to a normal force: only the sparse path's Coulomb guesses solve them
    if (findex_[r] >= 0 && !ws.coulomb_friction) return Outcome::Unsupported;
    bx_[2 * r] *= fps;
    cfm_[r] *= fps;
  }

  // ---- stage 2b/2c: rhs = c / h - J (v / h + M⁻¹ f), and A
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
      // M⁻¹ Jᵀ of this side: J_lin / m, invI J_ang (invI symmetric)
      double* JM = &jm_[r][6 * side];
      for (int c = 0; c < 3; ++c) JM[c] = J[c] * bs_[bi].inv_mass;
      dMultiply0_133(JM + 3, J + 3, bs_[bi].invI);
    }
  }
  build_a(m);

  // ---- stage 3: the solve
  if (m > 0) {
    if (!solve_sparse(ws, static_cast<unsigned>(m), a(), bx_.data(), nullptr,
                      static_cast<unsigned>(nub), lh_.data(), findex_.data()))
      return Outcome::SolveRefused;
    ++ws.sparse;
  }

  // ---- stage 4: constraint forces, feedback, velocities and poses
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
  return Outcome::Stepped;
}

// Stage 0 of body i: invI in the world frame and the gyroscopic torque added to tacc_g. Both
// depend only on R, the angular velocity, h and the body's constants, so an attempt that starts
// from the same bodies (the implicit-slip and guess re-solves restore them) takes the last ones.
void IslandStep::stage0(int i, double h) {
  BodyState& s = bs_[i];
  const dBodyID b = body_[i];
  Stage0& c = stage0_[i];
  const bool gyro = dBodyGetGyroscopicMode(b) != 0;
  const bool hit = reuse && c.valid && c.gyro == gyro && c.h == h &&
                   std::memcmp(c.R, s.R, sizeof c.R) == 0 &&
                   std::memcmp(c.avel, s.avel, sizeof c.avel) == 0;
  if (!hit) {
    c.valid = true;
    c.gyro = gyro;
    c.h = h;
    std::memcpy(c.R, s.R, sizeof c.R);
    std::memcpy(c.avel, s.avel, sizeof c.avel);
    dMatrix3 tmp;
    dMultiply2_333(tmp, inv_inertia_body_[i].data(), s.R);
    dMultiply0_333(c.invI, s.R, tmp);
    c.tau = false;
    if (gyro) {
      // Lacoursière's implicit gyroscopic torque, as stage 0: with I and L = I w in the world
      // frame, tau = (I (I - h [L]x)⁻¹ - 1) L / h
      dMatrix3 I, itild = {0}, itinv;
      dMultiply2_333(tmp, inertia_body_[i].data(), s.R);
      dMultiply0_333(I, s.R, tmp);
      dVector3 L;
      dMultiply0_331(L, I, s.avel);
      dSetCrossMatrixMinus(itild, L, 4);
      for (int k = 0; k < 12; ++k) itild[k] = itild[k] * h + I[k];
      dScaleVector3(L, 1.0 / h);  // (fps)
      if (dInvertMatrix3(itinv, itild) != 0) {
        dMultiply0_333(itild, I, itinv);
        itild[0] -= 1;
        itild[5] -= 1;
        itild[10] -= 1;
        dMultiply0_331(c.tau0, itild, L);
        c.tau = true;
      }
    }
  }
  std::memcpy(s.invI, c.invI, sizeof s.invI);
  if (c.tau)
    for (int k = 0; k < 3; ++k) s.tacc_g[k] += c.tau0[k];
}

// A's lower triangle (row stride dPAD(m), ODE's layout for the solver), body by body: the rows
// touching body b (in row order), their Jacobians on b gathered column by column, so that row
// p's products with rows q <= p, (M⁻¹ Jᵀ)_p · J_q, are six independent multiply-adds per q that
// vectorise across q (entry by entry, each a chain of dependent adds, was as slow as ODE's).
// The diagonal starts at the row's CFM / h. Into the other buffer than the last attempt's, which
// build_a_reusing copies from.
void IslandStep::build_a(int m) {
  cur_ ^= 1;
  if (m == 0) {
    prev_m_ = -1;
    return;
  }
  if (reuse && build_a_reusing(m)) {
    ++a_reused;
    remember_rows(m);
    return;
  }
  double* a = this->a();
  const int stride = dPAD(m);
  for (int r = 0; r < m; ++r) {  // (the solver reads row r up to column r + 1)
    double* row = &a[static_cast<std::size_t>(r) * stride];
    std::fill(row, row + std::min(r + 2, stride), 0.0);
    row[r] = cfm_[r];
  }
  std::array<int, kMaxRows> rows;
  std::array<double, kMaxRows> dot;
  for (int b = 0; b < kBodies; ++b) {
    int n = 0;
    for (int r = 0; r < m; ++r) {
      const int side = ra_[r] == b ? 0 : rb_[r] == b ? 1 : -1;
      if (side < 0) continue;
      rows[n] = r;
      side_[n] = side;
      for (int c = 0; c < 6; ++c) jb_[c][n] = j_[r][6 * side + c];
      ++n;
    }
    for (int p = 0; p < n; ++p) {
      const double* jm = &jm_[rows[p]][6 * side_[p]];
      const double m0 = jm[0], m1 = jm[1], m2 = jm[2], m3 = jm[3], m4 = jm[4], m5 = jm[5];
      const double *j0 = jb_[0].data(), *j1 = jb_[1].data(), *j2 = jb_[2].data(),
                   *j3 = jb_[3].data(), *j4 = jb_[4].data(), *j5 = jb_[5].data();
      for (int q = 0; q <= p; ++q)
        dot[q] = ((m0 * j0[q] + m1 * j1[q]) + (m2 * j2[q] + m3 * j3[q])) + (m4 * j4[q] + m5 * j5[q]);
      double* arow = &a[static_cast<std::size_t>(rows[p]) * stride];
      for (int q = 0; q <= p; ++q) arow[rows[q]] += dot[q];
    }
  }
  if (reuse)
    remember_rows(m);
  else
    prev_m_ = -1;  // (the other buffer no longer holds the remembered rows' A)
}

// A(p, q), q <= p, as build_a forms it: from the CFM (diagonal) or zero, (M⁻¹ Jᵀ)_p · J_q added
// body by body in ascending order, each product in build_a's association (the same bits: the
// build has no fused multiply-adds, IEEE products and sums round alike in vector lanes).
double IslandStep::a_entry(int p, int q) const {
  double s = p == q ? cfm_[p] : 0.0;
  const int lo = rb_[p] >= 0 && rb_[p] < ra_[p] ? rb_[p] : ra_[p];
  const int hi = lo == ra_[p] ? rb_[p] : ra_[p];
  for (const int b : {lo, hi}) {
    if (b < 0) continue;
    const int sq = ra_[q] == b ? 0 : rb_[q] == b ? 1 : -1;
    if (sq < 0) continue;
    const double* jm = &jm_[p][ra_[p] == b ? 0 : 6];
    const double* j = &j_[q][6 * sq];
    s += ((jm[0] * j[0] + jm[1] * j[1]) + (jm[2] * j[2] + jm[3] * j[3])) +
         (jm[4] * j[4] + jm[5] * j[5]);
  }
  return s;
}

// Reuse: A's entry between rows p > q equals the last attempt's between their matches p' > q'
// when both rows have the same Jacobians on the same bodies, whose invI (hence M⁻¹ Jᵀ) is the
// same: a pure function of equal inputs. Rows are matched in order (a re-solve emits the same
// joints in the same order; a row emitted as an explicit force instead, or a new contact, shifts
// the rest), so runs of matched rows copy as runs. New rows' entries, pairs whose order flipped
// and the diagonal (its CFM changes with the force-dependent bounds) are computed afresh
// (a_entry). False, with nothing written: too few rows match to pay (build_a then).
bool IslandStep::build_a_reusing(int m) {
  if (prev_m_ <= 0) return false;
  std::array<bool, kBodies> same;
  for (int b = 0; b < kBodies; ++b)
    same[b] = std::memcmp(bs_[b].invI, prev_invI_[b].data(), sizeof bs_[b].invI) == 0;
  if (std::none_of(same.begin(), same.end(), [](bool x) { return x; })) return false;
  const auto matches = [&](int p, int pp) {
    return ra_[p] == prev_ra_[pp] && rb_[p] == prev_rb_[pp] && same[ra_[p]] &&
           (rb_[p] < 0 || same[rb_[p]]) &&
           std::memcmp(j_[p].data(), prev_j_[pp].data(), sizeof(double) * 12) == 0;
  };
  int matched = 0, next = 0;
  for (int p = 0; p < m; ++p) {
    int found = -1;
    if (next < prev_m_ && matches(p, next)) {
      found = next;
    } else {
      for (int pp = 0; pp < prev_m_; ++pp)
        if (pp != next && matches(p, pp)) {
          found = pp;
          break;
        }
    }
    map_[p] = found;
    if (found >= 0) {
      ++matched;
      next = found + 1;
    }
  }
  if (2 * matched < m) return false;
  a_rows_new += static_cast<std::uint64_t>(m - matched);
  double* a = this->a();
  const double* prev = a_buf_[cur_ ^ 1].data();
  const int stride = dPAD(m), pstride = dPAD(prev_m_);
  for (int p = 0; p < m; ++p) {
    double* row = &a[static_cast<std::size_t>(p) * stride];
    const int mp = map_[p];
    if (mp < 0) {
      for (int q = 0; q < p; ++q) row[q] = a_entry(p, q);
    } else {
      const double* prow = &prev[static_cast<std::size_t>(mp) * pstride];
      for (int q = 0; q < p;) {
        const int mq = map_[q];
        if (mq < 0 || mq >= mp) {
          row[q] = a_entry(p, q);
          ++q;
          continue;
        }
        int e = q + 1;
        while (e < p && map_[e] == mq + (e - q) && map_[e] < mp) ++e;
        std::memcpy(row + q, prow + mq, sizeof(double) * static_cast<std::size_t>(e - q));
        q = e;
      }
    }
    row[p] = a_entry(p, p);
    if (p + 1 < stride) row[p + 1] = 0.0;
  }
  return true;
}

// This attempt's rows and bodies, for the next attempt's build_a_reusing.
void IslandStep::remember_rows(int m) {
  prev_m_ = m;
  for (int r = 0; r < m; ++r) {
    prev_j_[r] = j_[r];
    prev_ra_[r] = ra_[r];
    prev_rb_[r] = rb_[r];
  }
  for (int b = 0; b < kBodies; ++b) std::copy(bs_[b].invI, bs_[b].invI + 12, prev_invI_[b].begin());
}

// Stage 4's velocity update and dxStepBody: v += h (f_c + f) / m, w += invI h (t_c + t), then
// x += h v and q += h dq(w, q), normalised and turned into R by dBodySetQuaternion (ODE's own
// dNormalize4 and dQtoR, as dxStepBody); the accumulators are cleared.
void IslandStep::integrate(double h) {
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
    dBodySetQuaternion(b, q);
    dBodySetForce(b, 0, 0, 0);
    dBodySetTorque(b, 0, 0, 0);
  }
}

}  // namespace ernest::dynamics::detail
