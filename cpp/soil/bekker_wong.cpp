// Bekker–Wong with the DARTS changes: seed 004 §3.3, eqs 12–32. Equation numbers in comments.
#include "ernest/soil/bekker_wong.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "ernest/common/quadrature.hpp"
#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"
#include "ernest/common/vector_math.hpp"

namespace ernest::soil {

namespace {

// Nodes of up to four panels (three kinks) in fixed-capacity arrays: no heap allocation.
constexpr int kCapacity = 4 * BekkerWongModel::kMaxPointsPerPanel;

// Every angle of the model lies in [-pi/2, pi/2] (theta_f <= 90 deg since sinkage <= r), where
// these Taylor polynomials are accurate to < 1e-11; unlike std::cos they vectorise. They take
// t2 = t^2, so that cos and sin of the same angle share it.
inline double poly_cos_t2(double t2) {
  return 1.0 + t2 * (-1.0 / 2 + t2 * (1.0 / 24 + t2 * (-1.0 / 720 + t2 * (1.0 / 40320 +
         t2 * (-1.0 / 3628800 + t2 * (1.0 / 479001600 + t2 * (-1.0 / 87178291200.0 +
         t2 * (1.0 / 20922789888000.0))))))));
}

inline double poly_sin_t2(double t, double t2) {
  return t * (1.0 + t2 * (-1.0 / 6 + t2 * (1.0 / 120 + t2 * (-1.0 / 5040 + t2 * (1.0 / 362880 +
         t2 * (-1.0 / 39916800 + t2 * (1.0 / 6227020800.0 + t2 * (-1.0 / 1307674368000.0 +
         t2 * (1.0 / 355687428096000.0)))))))));
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

inline double clamp_unit(double v) { return std::min(1.0, std::max(-1.0, v)); }

// For a braking wheel (s < 0) j_x of eq 21 can change sign inside the contact patch, and |j_x|
// in eq 19 then has a kink that Gauss–Legendre handles poorly (~1% error at 4 points). With
// g(t) = t_f - t - (1 - s)(sin t_f - sin t): g' = (1 - s) cos t - 1 > 0 on (-t_c, t_c),
// t_c = acos(1 / (1 - s)), and g > 0 on [t_c, t_f); so there is at most one interior root,
// bracketed in (max(t_r, -t_c), t_c) where g is increasing. Returns NaN if there is none.
double jx_sign_change(double tf, double sin_tf, double tr, double s) {
  const double k = 1.0 - s;
  if (s >= 0.0) return kNaN;
  const double tc = std::acos(1.0 / k);
  if (tf <= tc) return kNaN;
  auto g = [&](double t) { return tf - t - k * (sin_tf - std::sin(t)); };
  double lo = std::max(tr, -tc), hi = tc;
  if (g(lo) >= 0.0) return kNaN;
  double t = 0.5 * (lo + hi);
  for (int it = 0; it < 30; ++it) {  // safeguarded Newton: stays inside the shrinking bracket
    const double gt = g(t);
    (gt < 0.0 ? lo : hi) = t;
    if (hi - lo < 1e-12) break;
    const double step = gt / (k * std::cos(t) - 1.0);
    double next = t - step;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - t) < 1e-13) { t = next; break; }
    t = next;
  }
  return t;
}

}  // namespace

void WheelGeometry::validate() const {
  require_in_range("WheelGeometry", "radius", radius, 1e-3, 10.0);
  require_in_range("WheelGeometry", "width", width, 1e-3, 10.0);
}

double slip_ratio(double vx, double vcx, double eps_slip, bool clamp_first) {
  // eq 12: driving vs braking decided by the directions of v_cx and v_x, not by |r w| vs |v_x|;
  // (1 - exp(-eps v_x^2)) takes s smoothly to 0 as longitudinal motion stops.
  const double reg = -std::expm1(-eps_slip * vx * vx);
  double s;
  if (vcx * vx <= 0.0) {
    const double den = vcx - vx;
    s = den != 0.0 ? vcx / den * reg : 0.0;
  } else {
    s = clamp_first ? -std::min(vcx / vx, 1.0) * reg : -vcx / vx * reg;
  }
  return clamp_unit(s);
}

BekkerWongModel::BekkerWongModel(const SoilParameters& soil, const WheelGeometry& wheel,
                                 int points_per_panel)
    : soil_(soil), wheel_(wheel) {
  soil_.validate();
  wheel_.validate();
  require_in_range("BekkerWongModel", "points_per_panel", points_per_panel, 1,
                   kMaxPointsPerPanel);
  ernest::gauss_legendre(points_per_panel, nodes_, weights_);
  const double r = wheel_.radius, b = wheel_.width, n = soil_.sinkage_exponent;
  k_eq_ = std::pow(r, n) * (soil_.k_c / b + soil_.k_phi);  // eq 17
  require(k_eq_ > 0.0, "SoilParameters: k_c / b + k_phi must be > 0 for this wheel width");
  const double phi = soil_.friction_angle;
  tan_phi_ = std::tan(phi);
  const double xc = M_PI / 4.0 - phi / 2.0;                  // eq 27
  d1_ = 1.0 / std::tan(xc) + std::tan(xc + phi);             // eq 25
  const double cot_xc = 1.0 / std::tan(xc);
  d2_ = phi > 0.0 ? cot_xc + cot_xc * cot_xc * tan_phi_ : cot_xc;  // eq 26: cot^2 Xc / cot phi
}

// Also compiled for AVX2 (common/vector_math.hpp): the node loops below run 4 wide there, with
// the same bits.
ERNEST_ALSO_AVX2
SoilSplit BekkerWongModel::integrate(const ContactState& st, bool lateral,
                                     const double* slip, bool shear) const {
  const char* o = "ContactState";
  require_finite(o, "sinkage", st.sinkage);
  require_finite(o, "vx", st.vx);
  require_finite(o, "vy", st.vy);
  require_finite(o, "vcx", st.vcx);
  require_finite(o, "vcy", st.vcy);

  const SoilParameters& p = soil_;
  const double r = wheel_.radius, b = wheel_.width;
  SoilSplit out;
  if (slip) require_finite("BekkerWongModel::split", "slip", *slip);
  const double s = slip ? clamp_unit(*slip) : slip_ratio(st.vx, st.vcx);  // eq 12
  out.slip = s;
  if (!(st.sinkage > 0.0)) return out;  // above the ground: no force

  const double h = std::min(st.sinkage, r);
  out.sinkage = h;
  const double cos_tf = 1.0 - h / r;
  const double tf = std::acos(cos_tf);  // eq 13
  const double sin_tf = std::sqrt(h / r * (2.0 - h / r));  // sin(acos(1 - h/r)), no cancellation
  // eq 16: t_rest -> 0 at full rest makes the stress distribution symmetric (no net F_x).
  const double t_rest =
      std::min((st.vx * st.vx + st.vcx * st.vcx) / (p.eps_motion * p.eps_motion), 1.0);
  const double tm = t_rest * (p.a0 + p.a1 * s) * tf;                          // eq 14
  const double tr = t_rest * (p.b0 + p.b1 * s) * tf + (t_rest - 1.0) * tf;    // eq 15
  out.theta_f = tf;
  out.theta_m = tm;
  out.theta_r = tr;

  // sign(v_x) of eqs 30 and 32, regularised (eps_direction, ours; 0 = the paper's sign).
  const double sdir = p.eps_direction > 0.0 ? clamp_unit(st.vx / p.eps_direction)
                                            : (st.vx > 0.0) - (st.vx < 0.0);
  // Sideslip angle beta = atan(v_y / |v_x|) enters eq 22 only through tan(beta).
  const double tan_beta = st.vy / std::max(std::abs(st.vx), 1e-12);
  const double n = p.sinkage_exponent;
  const double one_minus_s = 1.0 - s;
  const double weight_density = p.density * p.gravity;  // rho g of Hegedus' eq 24

  // Gauss–Legendre panels split where the integrands have kinks: theta = 0 (the bulldozing depth
  // profile of eq 23 peaks there), theta_m (the theta' mapping of eq 18) and, when braking, the
  // sign change of j_x (eqs 19, 21). All panels' nodes go into one array so that each integrand
  // below is a single vectorised pass.
  double cuts[5] = {tr, 0.0, tm, tf, tf};
  int ncuts = 4;
  const double kink = jx_sign_change(tf, sin_tf, tr, s);
  if (kink > tr && kink < tf) {
    cuts[ncuts++] = kink;
    std::sort(cuts, cuts + ncuts);
  }
  const int np = static_cast<int>(nodes_.size());
  // Plain loops over the nodes (the compiler vectorises them), the transcendentals of all nodes
  // in batched calls (common/vector_math.hpp).
  alignas(32) double theta[kCapacity], w[kCapacity], c[kCapacity], sn[kCapacity];
  alignas(32) double cos_eff[kCapacity], pw[kCapacity], ex[2 * kCapacity], dfac[kCapacity];
  int m = 0, m_rear = 0;  // nodes; those behind theta_m (the panels below that cut)
  for (int panel = 0; panel + 1 < ncuts; ++panel) {
    const double lo = cuts[panel], hi = cuts[panel + 1];
    if (!(hi > lo)) continue;
    const double half = 0.5 * (hi - lo), mid = 0.5 * (hi + lo);
    for (int k = 0; k < np; ++k, ++m) {
      theta[m] = mid + half * nodes_[k];
      w[m] = half * weights_[k];
    }
    if (hi <= tm) m_rear = m;
  }
  if (m == 0) return out;

  for (int i = 0; i < m; ++i) {
    const double t = theta[i], t2 = t * t;
    c[i] = poly_cos_t2(t2);
    sn[i] = poly_sin_t2(t, t2);
  }
  // eq 18: theta' maps [theta_r, theta_m] onto [theta_f, theta_m]; theta' = theta in front.
  const double map_slope = (tf - tm) / (tm - tr);
  // dfac: d(cos theta' - cos theta_f) / d theta_f at fixed theta (the sinkage derivative below):
  // sin theta_f - sin theta' d theta' / d theta_f, with d theta' / d theta_f = 1 + (theta_r /
  // theta_f) map_slope behind theta_m (eqs 14-15 scale theta_m and theta_r with theta_f, so
  // map_slope does not depend on it) and 0 in front.
  const double dmap = 1.0 + tr / tf * map_slope;
  for (int i = 0; i < m_rear; ++i) {
    const double tmap = tf - (theta[i] - tr) * map_slope, tmap2 = tmap * tmap;
    cos_eff[i] = poly_cos_t2(tmap2);
    dfac[i] = sin_tf - dmap * poly_sin_t2(tmap, tmap2);
  }
  for (int i = m_rear; i < m; ++i) {
    cos_eff[i] = c[i];
    dfac[i] = sin_tf;
  }
  // eq 17, with (cos theta' - cos theta_f)^n written as exp(n log(.)).
  for (int i = 0; i < m; ++i) pw[i] = std::max(cos_eff[i] - cos_tf, 1e-300);
  log_n(pw, pw, m);
  for (int i = 0; i < m; ++i) pw[i] *= n;
  if (!shear) {  // eqs 30 and 32 without the shear: as the full pass below, term by term
    double s_sig_sn = 0.0, s_sig_c = 0.0;
    exp_n(pw, pw, m);
    for (int i = 0; i < m; ++i) {
      const double sigma = cos_eff[i] > cos_tf ? k_eq_ * pw[i] : 0.0;
      const double w_sig = w[i] * sigma;
      s_sig_sn += w_sig * sn[i];
      s_sig_c += w_sig * c[i];
    }
    out.fx_pressure = -sdir * r * b * s_sig_sn;
    out.fz_pressure = r * b * s_sig_c;
    return out;
  }
  // eqs 19 and 21 with |j_x| (unit shear level: eq 28 scales it by clamp(-v_cx / eps)), and
  // eqs 20 and 22 for y: the exponents of both in one batch.
  const double ky = r * one_minus_s * tan_beta;
  const double inv_kx = 1.0 / p.shear_modulus_x, inv_ky = 1.0 / p.shear_modulus_y;
  for (int i = 0; i < m; ++i) {
    const double jx = r * (tf - theta[i] - one_minus_s * (sin_tf - sn[i]));
    ex[i] = -std::abs(jx) * inv_kx;
    ex[m + i] = -std::abs(ky * (tf - theta[i])) * inv_ky;
  }
  exp_n(pw, pw, m);
  exp_n(ex, ex, lateral ? 2 * m : m);
  double s_sig_sn = 0.0, s_sig_c = 0.0, s_tau_c = 0.0, s_tau_sn = 0.0, s_tau = 0.0, s_tau_y = 0.0;
  double s_dsig_c = 0.0;  // int d sigma / d theta_f cos theta (eq 17 differentiated)
  const double h_rear = h / std::max(-tr, 1e-300), h_front = h / tf, inv_rb = 1.0 / (r * b);
  for (int i = 0; i < m; ++i) {
    const double sigma = cos_eff[i] > cos_tf ? k_eq_ * pw[i] : 0.0;
    const double strength = p.cohesion + sigma * tan_phi_;  // Mohr–Coulomb of eqs 19–20
    const double w_tau = w[i] * (strength * (1.0 - ex[i])), w_sig = w[i] * sigma;
    s_sig_sn += w_sig * sn[i];
    s_sig_c += w_sig * c[i];
    s_tau_c += w_tau * c[i];
    s_tau_sn += w_tau * sn[i];
    s_tau += w_tau;
    // d sigma / d theta_f = n sigma / (cos theta' - cos theta_f) * dfac (no new transcendental)
    const double gap = cos_eff[i] - cos_tf;
    if (gap > 0.0) s_dsig_c += w[i] * (n * sigma / gap * dfac[i]) * c[i];
    if (lateral) {
      // Hegedus bulldozing eqs 23–27 with h(theta) linear from h at the reference point
      // (theta = 0) to 0 at theta_r and theta_f.
      const double t = theta[i];
      const double h_theta = std::max(t < 0.0 ? (t - tr) * h_rear : (tf - t) * h_front, 0.0);
      const double rb = d1_ * (p.cohesion * h_theta + d2_ * weight_density * h_theta * h_theta / 2.0);
      const double fs = rb * (r - h_theta * c[i]);
      s_tau_y += w[i] * (strength * (1.0 - ex[m + i]) + fs * inv_rb);
    }
  }
  out.fx_pressure = -sdir * r * b * s_sig_sn;  // eq 30, compaction resistance
  out.fz_pressure = r * b * s_sig_c;           // eq 32, normal stress
  out.fx_shear = r * b * s_tau_c;              // eq 30, shear
  out.fz_shear = sdir * r * b * s_tau_sn;      // eq 32, shear
  out.torque_shear = r * r * b * s_tau;
  if (lateral) out.fy_shear = r * b * s_tau_y;  // eq 31
  // d F_z / d h: sigma vanishes at both ends (theta' = theta_f at theta_r and theta_f), so the
  // moving limits add nothing (Leibniz); d theta_f / d h = 1 / (r sin theta_f) from eq 13.
  // Beyond the radius the sinkage is clamped: no change.
  if (st.sinkage < r) out.dfz_pressure_dh = b * s_dsig_c / sin_tf;
  return out;
}

double BekkerWongModel::slip_ratio(double vx, double vcx) const {
  return soil::slip_ratio(vx, vcx, soil_.eps_slip, soil_.slip_clamp_first);
}

SoilSplit BekkerWongModel::split(const ContactState& state) const {
  return integrate(state, true, nullptr);
}

SoilSplit BekkerWongModel::split(const ContactState& state, double slip) const {
  return integrate(state, true, &slip);
}

SoilSplit BekkerWongModel::split_pressure(const ContactState& state, double slip) const {
  return integrate(state, false, &slip, false);
}

WheelSoilForce BekkerWongModel::evaluate(const ContactState& st) const {
  const SoilParameters& p = soil_;
  // eqs 28–29: shear opposes the contact velocity, scaled to 0 below eps_contact.
  const double sx = clamp_unit(-st.vcx / p.eps_contact_x);
  const double sy = clamp_unit(-st.vcy / p.eps_contact_y);
  const SoilSplit t = integrate(st, sy != 0.0, nullptr);
  WheelSoilForce out;
  out.slip = t.slip;
  out.theta_f = t.theta_f;
  out.theta_m = t.theta_m;
  out.theta_r = t.theta_r;
  out.sinkage = t.sinkage;
  out.fx = t.fx_pressure + sx * t.fx_shear;  // eq 30
  out.fy = sy * t.fy_shear;                  // eq 31
  // eq 32, floored at 0: for a braking wheel at a few mm of sinkage in soft soil (n = 1.9) the
  // cohesive shear of eq 19 can outweigh the near-zero normal stress and make the sum slightly
  // negative (~ -0.03 N); the soil cannot pull a wheel into the ground.
  out.fz = std::max(0.0, t.fz_pressure + sx * t.fz_shear);
  out.axle_torque = sx * t.torque_shear;
  return out;
}

void BekkerWongModel::evaluate_batch(
    const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 5, Eigen::RowMajor>>& states,
    Eigen::Ref<Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>> forces) const {
  if (forces.rows() != states.rows()) {
    throw std::invalid_argument("evaluate_batch: forces has " + std::to_string(forces.rows()) +
                                " rows but states has " + std::to_string(states.rows()));
  }
  for (Eigen::Index i = 0; i < states.rows(); ++i) {
    if (i % 4096 == 0) poll_interrupt();  // Ctrl-C between rows (common/interrupt.hpp)
    WheelSoilForce f;
    try {
      f = evaluate(ContactState{states(i, 0), states(i, 1), states(i, 2), states(i, 3), states(i, 4)});
    } catch (const std::invalid_argument& e) {  // name the parameter and the row
      throw std::invalid_argument("evaluate_batch: states row " + std::to_string(i) + ": " + e.what());
    }
    forces(i, 0) = f.fx;
    forces(i, 1) = f.fy;
    forces(i, 2) = f.fz;
    forces(i, 3) = f.axle_torque;
  }
}

}  // namespace ernest::soil
