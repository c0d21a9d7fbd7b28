// Coulomb's law with the final normal force on ODE's answer (solve_coulomb, coulomb_lcp.hpp):
// from ODE's active set, one dense non-symmetric solve per guess, checked as Dantzig's method ends.
#include "ernest/solver/coulomb_lcp.hpp"

#include <ode/ode.h>

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace ernest::solver {

// Seed 004 §3.4's Coulomb friction bounds a friction row i (findex[i] = k) by mu_i times the
// final normal force x_k. ODE's Dantzig solver takes x_k from before it adds the friction rows,
// which can be tens of per cent off, so a sliding contact's friction follows the pivoting order,
// not the normal force. solve_coulomb corrects ODE's answer: from the active set it found, each
// row is free (solved), at a constant bound, or, for friction, at +-mu_i x_k (a linear relation:
// x_k's column gains +-mu_i times row i's), which makes one dense non-symmetric linear solve per
// guess; the result is checked as Dantzig's method ends (free rows inside their bounds, rows at a
// bound pushed onto it) and a wrong row flipped, kAttempts times at most. Returns false, leaving
// ODE's answer, if no guess held. ws.a_copy, bx_copy, lh_copy, findex_copy: the problem before
// ODE's solve.
bool solve_coulomb(LcpWorkspace& ws, unsigned n, unsigned nub, double* pairsbx,
                   double* outer_w) {
  constexpr int kMax = LdltPlan::kMaxRows;
  constexpr int kAttempts = 6;
  constexpr std::int8_t kIn = 0, kHi = 1, kLo = 2;  // a row's place: inside, at hi, at lo
  using Mat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMax, kMax>;
  using Vec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMax, 1>;
  const unsigned stride = dPAD(n);
  const double* a = ws.a_copy.data();
  const double* lh = ws.lh_copy.data();
  const int* findex = ws.findex_copy.data();
  const auto A = [&](unsigned i, unsigned j) {  // ODE fills the lower triangle
    return i >= j ? a[i * stride + j] : a[j * stride + i];
  };
  const auto b = [&](unsigned i) { return ws.bx_copy[2 * i]; };
  const auto friction = [&](unsigned i) { return i >= nub && findex[i] >= 0; };
  const auto unbounded = [&](unsigned i) {
    return i < nub || (!friction(i) && lh[2 * i] == -dInfinity && lh[2 * i + 1] == dInfinity);
  };
  std::array<double, kMax> x, w;
  std::array<std::int8_t, kMax> place;
  std::array<int, kMax> col;
  double bscale = 1.0;
  for (unsigned i = 0; i < n; ++i) {
    x[i] = pairsbx[2 * i + 1];
    bscale = std::max(bscale, std::abs(b(i)));
  }
  const auto residuals = [&] {
    for (unsigned i = 0; i < n; ++i) {
      double s = -b(i);
      for (unsigned j = 0; j < n; ++j) s += A(i, j) * x[j];
      w[i] = s;
    }
  };
  const double tol_w = 1e-9 * bscale;
  // ODE's active set: friction rows pushed by their residual, others where ODE left them. With
  // no friction row at a bound ODE's answer is already Coulomb's (its bounds were not used).
  residuals();
  bool clamped = false;
  for (unsigned i = 0; i < n && !clamped; ++i) {
    clamped = friction(i) && (std::abs(w[i]) > tol_w ||
                              std::abs(x[i]) > std::abs(lh[2 * i + 1] * x[findex[i]]));
  }
  if (!clamped) return true;
  for (unsigned i = 0; i < n; ++i) {
    place[i] = kIn;
    if (unbounded(i)) continue;
    if (friction(i)) {
      if (w[i] < -tol_w && x[i] > 0.0) place[i] = kHi;
      if (w[i] > tol_w && x[i] < 0.0) place[i] = kLo;
    } else if (x[i] == lh[2 * i + 1]) {
      place[i] = kHi;
    } else if (x[i] == lh[2 * i]) {
      place[i] = kLo;
    }
  }
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    int m = 0;
    for (unsigned i = 0; i < n; ++i) col[i] = place[i] == kIn ? m++ : -1;
    Mat M = Mat::Zero(m, m);
    Vec r(m);
    for (unsigned i = 0; i < n; ++i) {
      if (col[i] < 0) continue;
      double ri = b(i);
      for (unsigned j = 0; j < n; ++j) {
        const double aij = A(i, j);
        if (place[j] == kIn) {
          M(col[i], col[j]) += aij;
        } else if (friction(j)) {  // x_j = +-mu_j x_k
          const unsigned k = static_cast<unsigned>(findex[j]);
          const double s = (place[j] == kHi ? 1.0 : -1.0) * std::abs(lh[2 * j + 1]);
          if (place[k] == kIn) {
            M(col[i], col[k]) += s * aij;
          } else {
            ri -= aij * s * lh[2 * k + (place[k] == kHi ? 1 : 0)];
          }
        } else {
          ri -= aij * lh[2 * j + (place[j] == kHi ? 1 : 0)];
        }
      }
      r[col[i]] = ri;
    }
    Vec y;
    if (m > 0) y = Eigen::PartialPivLU<Mat>(M).solve(r);
    double xscale = 1.0;
    for (unsigned i = 0; i < n; ++i) {
      if (place[i] == kIn) x[i] = y[col[i]];
      else if (!friction(i)) x[i] = lh[2 * i + (place[i] == kHi ? 1 : 0)];
    }
    for (unsigned i = 0; i < n; ++i) {
      if (place[i] != kIn && friction(i))
        x[i] = (place[i] == kHi ? 1.0 : -1.0) * std::abs(lh[2 * i + 1]) * x[findex[i]];
      if (!std::isfinite(x[i])) return false;
      xscale = std::max(xscale, std::abs(x[i]));
    }
    residuals();
    const double tol_x = 1e-9 * xscale;
    bool wrong = false;
    for (unsigned i = 0; i < n; ++i) {
      if (unbounded(i)) continue;
      double lo = lh[2 * i], hi = lh[2 * i + 1];
      if (friction(i)) {
        hi = std::abs(hi) * std::abs(x[findex[i]]);
        lo = -hi;
      }
      std::int8_t want = place[i];
      if (place[i] == kIn) {
        if (x[i] > hi + tol_x) want = kHi;
        if (x[i] < lo - tol_x) want = kLo;
      } else if ((place[i] == kHi && w[i] > tol_w) || (place[i] == kLo && w[i] < -tol_w)) {
        want = kIn;  // pulled off its bound
      }
      wrong = wrong || want != place[i];
      place[i] = want;
    }
    if (wrong) continue;
    for (unsigned i = 0; i < n; ++i) pairsbx[2 * i + 1] = x[i];
    if (outer_w) {
      for (unsigned i = 0; i < n; ++i) outer_w[i] = place[i] == kIn ? 0.0 : w[i];
    }
    return true;
  }
  return false;
}

}  // namespace ernest::solver
