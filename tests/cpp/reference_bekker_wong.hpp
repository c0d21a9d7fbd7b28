// Independent, deliberately plain re-statement of seed 004 eqs 12–32: scalar std:: maths and
// adaptive Gauss–Kronrod quadrature (split at theta_m and 0, where the integrands have kinks).
// Used by the tests to check the vectorised model and by the benchmark as the naive baseline.
#pragma once

#include <algorithm>
#include <array>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <cmath>
#include <vector>

#include "ernest/common/quadrature.hpp"

#include "ernest/soil/bekker_wong.hpp"

namespace ernest::soil::reference {

/// fixed_points = 0: adaptive Gauss–Kronrod (the accuracy reference); > 0: that many
/// Gauss–Legendre points on each of the panels [theta_r, 0, theta_m, theta_f] (the naive baseline).
inline std::array<double, 4> evaluate(const SoilParameters& p, const WheelGeometry& g,
                                      const ContactState& st, int gk_depth = 15,
                                      int fixed_points = 0) {
  const double r = g.radius, b = g.width;
  if (!(st.sinkage > 0.0)) return {0, 0, 0, 0};
  const double h = std::min(st.sinkage, r);
  // eq 12
  double s;
  const double reg = 1.0 - std::exp(-p.eps_slip * st.vx * st.vx);
  if (st.vcx * st.vx <= 0.0) {
    s = (st.vcx - st.vx) != 0.0 ? st.vcx / (st.vcx - st.vx) * reg : 0.0;
  } else {
    // SoilParameters::slip_clamp_first (ours): the braking ratio clamped before the factor
    s = p.slip_clamp_first ? -std::min(st.vcx / st.vx, 1.0) * reg : -st.vcx / st.vx * reg;
  }
  s = std::clamp(s, -1.0, 1.0);
  const double tf = std::acos(1.0 - h / r);                                          // eq 13
  const double trest = std::min((st.vx * st.vx + st.vcx * st.vcx) /
                                (p.eps_motion * p.eps_motion), 1.0);                 // eq 16
  const double tm = trest * (p.a0 + p.a1 * s) * tf;                                  // eq 14
  const double tr = trest * (p.b0 + p.b1 * s) * tf + (trest - 1.0) * tf;             // eq 15
  const double n = p.sinkage_exponent;
  auto sigma = [&](double t) {                                                       // eqs 17–18
    const double tp = t >= tm ? t : tf - (t - tr) / (tm - tr) * (tf - tm);
    const double d = std::cos(tp) - std::cos(tf);
    return d > 0 ? std::pow(r, n) * (p.k_c / b + p.k_phi) * std::pow(d, n) : 0.0;
  };
  const double sign_vcx = st.vcx > 0 ? 1.0 : (st.vcx < 0 ? -1.0 : 0.0);
  const double sign_vcy = st.vcy > 0 ? 1.0 : (st.vcy < 0 ? -1.0 : 0.0);
  const double kx = -sign_vcx * std::min(std::abs(st.vcx) / p.eps_contact_x, 1.0);  // eq 28
  const double ky = -sign_vcy * std::min(std::abs(st.vcy) / p.eps_contact_y, 1.0);  // eq 29
  const double sv = p.eps_direction > 0 ? std::clamp(st.vx / p.eps_direction, -1.0, 1.0)
                                        : (st.vx > 0 ? 1.0 : (st.vx < 0 ? -1.0 : 0.0));
  const double tanphi = std::tan(p.friction_angle);
  auto tau_x = [&](double t) {                                                       // eqs 19, 21
    const double jx = r * (tf - t - (1 - s) * (std::sin(tf) - std::sin(t)));
    return kx * (p.cohesion + sigma(t) * tanphi) * (1 - std::exp(-std::abs(jx) / p.shear_modulus_x));
  };
  const double xc = M_PI / 4 - p.friction_angle / 2;                                // eq 27
  const double d1 = 1 / std::tan(xc) + std::tan(xc + p.friction_angle);             // eq 25
  const double d2 = 1 / std::tan(xc) + std::pow(1 / std::tan(xc), 2) * tanphi;      // eq 26
  const double tanb = std::tan(std::atan(st.vy / std::max(std::abs(st.vx), 1e-12)));
  auto tau_y = [&](double t) {                                                       // eqs 20, 22–24
    const double jy = r * (1 - s) * (tf - t) * tanb;
    const double ht = t >= 0 ? h * (tf - t) / tf : h * (t - tr) / (-tr);
    const double rb = d1 * (p.cohesion * ht + d2 * p.density * p.gravity * ht * ht / 2);
    const double fs = rb * (r - ht * std::cos(t));
    return ky * ((p.cohesion + sigma(t) * tanphi) * (1 - std::exp(-std::abs(jy) / p.shear_modulus_y)) +
                 fs / (r * b));
  };
  std::vector<double> xs, ws;
  if (fixed_points > 0) ernest::gauss_legendre(fixed_points, xs, ws);
  auto integrate = [&](auto f) {
    using Q = boost::math::quadrature::gauss_kronrod<double, 61>;
    double total = 0;
    const double cuts[4] = {tr, 0.0, tm, tf};
    for (int i = 0; i < 3; ++i) {
      if (!(cuts[i + 1] > cuts[i])) continue;
      if (fixed_points == 0) {
        total += Q::integrate(f, cuts[i], cuts[i + 1], gk_depth, 1e-12);
      } else {
        const double half = 0.5 * (cuts[i + 1] - cuts[i]), mid = 0.5 * (cuts[i + 1] + cuts[i]);
        for (size_t k = 0; k < xs.size(); ++k) total += half * ws[k] * f(mid + half * xs[k]);
      }
    }
    return total;
  };
  const double fx = r * b * integrate([&](double t) {
    return tau_x(t) * std::cos(t) - sv * sigma(t) * std::sin(t); });                 // eq 30
  const double fy = r * b * integrate(tau_y);                                        // eq 31
  const double fz = std::max(0.0, r * b * integrate([&](double t) {
    return sv * tau_x(t) * std::sin(t) + sigma(t) * std::cos(t); }));  // eq 32, floored like the model
  const double torque = r * r * b * integrate(tau_x);
  return {fx, fy, fz, torque};
}

}  // namespace ernest::soil::reference
