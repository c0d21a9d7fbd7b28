// Seed 004 Fig. 25: maximum roll torque before lift-off, as a linear program solved by GLPK.
#include "ernest/statics/liftoff.hpp"

#include <glpk.h>

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

namespace ernest::statics {

void LiftoffOptions::validate() const {
  require_in_range("LiftoffOptions", "min_load", min_load, 0.0, 1e6);
  require(!std::isnan(torque_limit) && torque_limit > 0.0,
          "LiftoffOptions.torque_limit = " + std::to_string(torque_limit) +
              " is outside the allowed range (0, inf]");
}

LoadPose slope_pose(double slope, double heading, double psi) {
  require_in_range("slope_pose", "slope", slope, -1.4, 1.4);
  require_finite("slope_pose", "heading", heading);
  require_in_range("slope_pose", "psi", psi, -M_PI, M_PI);
  LoadPose p;
  // pitch nose-up by the slope for heading 0 (as RoverSim::reset tilts the chassis), heading in
  // the plane
  const Eigen::Quaterniond q(Eigen::AngleAxisd(-slope, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()));
  p.chassis_quaternion << q.w(), q.x(), q.y(), q.z();
  p.psi = psi;
  p.phi = 0.0;
  p.ground_normal << -std::sin(slope), 0.0, std::cos(slope);
  return p;
}

namespace {

struct GlpDeleter {
  void operator()(glp_prob* p) const { glp_delete_prob(p); }
};

// max (sense +1) or min (sense -1) of tau subject to A f - t tau = b, f >= min_load, |tau| <= limit.
// Returns false when infeasible.
bool solve_lp(const LoadEquations& e, const LiftoffOptions& o, int sense, LiftoffLimit& out) {
  std::unique_ptr<glp_prob, GlpDeleter> lp(glp_create_prob());
  glp_set_obj_dir(lp.get(), sense > 0 ? GLP_MAX : GLP_MIN);
  glp_add_rows(lp.get(), 4);
  glp_add_cols(lp.get(), 5);
  for (int r = 0; r < 4; ++r) glp_set_row_bnds(lp.get(), r + 1, GLP_FX, e.b[r], e.b[r]);
  for (int c = 0; c < 4; ++c) glp_set_col_bnds(lp.get(), c + 1, GLP_LO, o.min_load, 0.0);
  if (std::isinf(o.torque_limit))
    glp_set_col_bnds(lp.get(), 5, GLP_FR, 0.0, 0.0);
  else
    glp_set_col_bnds(lp.get(), 5, GLP_DB, -o.torque_limit, o.torque_limit);
  glp_set_obj_coef(lp.get(), 5, 1.0);
  // constraint matrix in GLPK's 1-based triplets: columns f_1..f_4 then tau
  int ia[1 + 20], ja[1 + 20];
  double ar[1 + 20];
  int k = 0;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 5; ++c) {
      const double v = c < 4 ? e.A(r, c) : -e.t[r];
      if (v == 0.0) continue;
      ++k;
      ia[k] = r + 1;
      ja[k] = c + 1;
      ar[k] = v;
    }
  }
  glp_load_matrix(lp.get(), k, ia, ja, ar);
  glp_smcp parm;
  glp_init_smcp(&parm);
  parm.msg_lev = GLP_MSG_OFF;
  parm.presolve = GLP_ON;  // reports an infeasible problem instead of iterating on it
  const int rc = glp_simplex(lp.get(), &parm);
  if (rc == GLP_ENOPFS) return false;
  if (rc != 0) throw std::runtime_error("max_roll_torque: GLPK simplex failed (code " +
                                        std::to_string(rc) + ")");
  const int status = glp_get_status(lp.get());
  if (status == GLP_NOFEAS || status == GLP_INFEAS) return false;
  if (status == GLP_UNBND) {  // cannot happen with A regular (loads sum to the weight)
    out.torque = sense * kInf;
    return true;
  }
  if (status != GLP_OPT)
    throw std::runtime_error("max_roll_torque: GLPK status " + std::to_string(status));
  out.torque = glp_get_col_prim(lp.get(), 5);
  for (int c = 0; c < 4; ++c) out.loads[c] = glp_get_col_prim(lp.get(), c + 1);
  out.torque_limited = std::isfinite(o.torque_limit) &&
                       std::abs(std::abs(out.torque) - o.torque_limit) <= 1e-9 * o.torque_limit;
  out.lifted_wheel = -1;
  if (!out.torque_limited) {
    int w = 0;
    for (int c = 1; c < 4; ++c)
      if (out.loads[c] < out.loads[w]) w = c;
    out.lifted_wheel = w;
  }
  return true;
}

}  // namespace

LiftoffResult max_roll_torque(const MassModel& model, const RoverGeometry& geometry,
                              const LoadPose& pose, const LiftoffOptions& options) {
  options.validate();
  LoadPose p = pose;
  p.loads.setZero();
  p.roll_torque = 0.0;
  const LoadEquations e = load_equations(model, geometry, p);  // validates model, geometry, pose
  LiftoffResult r;
  Eigen::FullPivLU<Eigen::Matrix4d> lu(e.A);
  require(lu.isInvertible(), "max_roll_torque: the pose's statics are singular");
  r.loads_at_zero = lu.solve(e.b);
  r.feasible = solve_lp(e, options, +1, r.positive);
  if (r.feasible) r.feasible = solve_lp(e, options, -1, r.negative);
  return r;
}

}  // namespace ernest::statics
