// Our own island step: what resolve() (island_step.cpp) checks before it reuses the last step's
// rows, and the caps it sets again (island_step.hpp says why and when). Everything is compared
// bit for bit: a resolve must give the bits of a rebuild.
#include <algorithm>
#include <cstring>

#include "ernest/solver/island_step.hpp"

namespace ernest::solver {

namespace {

bool same_bits(const double* x, const double* y, int n) {
  return std::memcmp(x, y, sizeof(double) * static_cast<std::size_t>(n)) == 0;
}

}  // namespace

// resolve()'s checks (island_step.hpp): everything step() reads but the attempt's targets and
// caps (contacts' mu and slip, linear motors' fmax and CFM: the rows' bounds and CFMs, not which
// rows there are) and the forces on the bodies is as the kept step read it. Same: the caps too,
// and the workspace still holds the kept step's factor.
IslandStep::Match IslandStep::same_problem(dWorldID world, double h, const LcpWorkspace& ws) {
  constexpr Match kDifferent = Match::Different;
  if (!kept_ || kept_buf_ == cur_ || !ws.enabled || n_attempt_ != kept_n_attempt_) return kDifferent;
  bool caps = m_ > 0 && ws.factors != kept_factor_;  // another solve factorised since
  dVector3 g;
  dWorldGetGravity(world, g);
  const double world_now[8] = {h, dWorldGetERP(world), dWorldGetCFM(world),
                               dWorldGetContactSurfaceLayer(world),
                               dWorldGetContactMaxCorrectingVel(world), g[0], g[1], g[2]};
  const double world_kept[8] = {kept_h_, kept_erp_, world_cfm_, min_depth_, max_vel_,
                                kept_gravity_[0], kept_gravity_[1], kept_gravity_[2]};
  if (!same_bits(world_now, world_kept, 8) || !bodies_supported()) return kDifferent;
  for (int i = 0; i < kBodies; ++i) {
    const dBodyID b = body_[i];
    const double* kept = kept_state_[i].data();
    if (!same_bits(dBodyGetPosition(b), kept, 3) || !same_bits(dBodyGetQuaternion(b), kept + 3, 4) ||
        !same_bits(dBodyGetRotation(b), kept + 7, 12) ||
        !same_bits(dBodyGetLinearVel(b), kept + 19, 3) ||
        !same_bits(dBodyGetAngularVel(b), kept + 22, 3))
      return kDifferent;
  }
  const Joint* before = buffer(kept_buf_);
  const Joint* now = buffer(cur_);
  for (int k = 0; k < n_attempt_; ++k) {
    const Joint &x = now[k], &y = before[k];
    if (x.kind != y.kind || x.a != y.a || x.b != y.b || x.fb != y.fb) return kDifferent;
    if (x.kind == Kind::LMotor) {
      if (!same_bits(x.lm_axis, y.lm_axis, 3) || (x.lm_fmax > 0.0) != (y.lm_fmax > 0.0))
        return kDifferent;
      const double u[2] = {x.lm_fmax, x.lm_cfm}, v[2] = {y.lm_fmax, y.lm_cfm};
      caps = caps || !same_bits(u, v, 2);
      continue;
    }
    const dContact &p = x.contact, &q = y.contact;
    if (p.surface.mode != q.surface.mode) return kDifferent;
    const auto fields = [](const dContact& c, double* f) {  // all but the motions and caps
      const dSurfaceParameters& s = c.surface;
      const double v[17] = {s.rho, s.rho2, s.rhoN, s.bounce, s.bounce_vel, s.soft_erp, s.soft_cfm,
                            c.geom.depth, c.geom.pos[0], c.geom.pos[1], c.geom.pos[2],
                            c.geom.normal[0], c.geom.normal[1], c.geom.normal[2], c.fdir1[0],
                            c.fdir1[1], c.fdir1[2]};
      std::copy(v, v + 17, f);
    };
    double u[17], v[17];
    fields(p, u);
    fields(q, v);
    if (!same_bits(u, v, 17)) return kDifferent;
    // the same friction rows (mu > 0: contact_rows), perhaps other bounds and CFMs
    if ((p.surface.mu > 0.0) != (q.surface.mu > 0.0) || (p.surface.mu2 > 0.0) != (q.surface.mu2 > 0.0))
      return kDifferent;
    const double cu[4] = {p.surface.mu, p.surface.mu2, p.surface.slip1, p.surface.slip2};
    const double cv[4] = {q.surface.mu, q.surface.mu2, q.surface.slip1, q.surface.slip2};
    caps = caps || !same_bits(cu, cv, 4);
  }
  return caps ? Match::Caps : Match::Same;
}

// An attempt joint's caps again (Match::Caps): its friction or motor rows' bounds and CFMs as
// contact_rows / lmotor_rows set them (the CFM over h as stage 2a), and those rows' diagonal of A
// as build_a sums it (the CFM, then each body's product: build_a's diag_).
void IslandStep::attempt_caps(const Joint& jt, double fps) {
  const int stride = dPAD(m_);
  const auto set = [&](int r, double cfm, double bound) {
    cfm_[r] = cfm * fps;
    lh_[2 * r] = -bound;
    lh_[2 * r + 1] = bound;
    double d = cfm_[r];
    for (int k = 0; k < n_diag_[r]; ++k) d += diag_[r][k];
    a_[static_cast<std::size_t>(r) * stride + r] = d;
  };
  if (jt.kind == Kind::LMotor) {
    if (jt.rows == 1) set(jt.first, jt.lm_cfm, jt.lm_fmax);
    return;
  }
  const dSurfaceParameters& s = jt.contact.surface;
  const double mu1 = s.mu < 0.0 ? 0.0 : s.mu;
  const double mu2 = (s.mode & dContactAxisDep) ? (s.mu2 < 0.0 ? 0.0 : s.mu2) : mu1;
  const double mu[2] = {mu1, mu2};
  const int slip[2] = {dContactSlip1, dContactSlip2};
  const double sval[2] = {s.slip1, s.slip2};
  int r = jt.first + 1;  // the friction rows follow the normal row
  for (int d = 0; d < 2 && r < jt.first + jt.rows; ++d) {
    if (!(mu[d] > 0.0)) continue;
    set(r++, (s.mode & slip[d]) ? sval[d] : world_cfm_, mu[d]);
  }
}

}  // namespace ernest::solver
