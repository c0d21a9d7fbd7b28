// The LCP as one sparse linear system (solve_sparse, sparse_lcp.hpp says what and when): the
// pattern of the solved rows for a new plan, the guessed active set solved with SparseLdlt, the
// friction rows at a bound as a low-rank correction (solve_clamped), and Dantzig's end checks.
#include "ernest/solver/sparse_lcp.hpp"

#include <emmintrin.h>
#include <ode/ode.h>

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace ernest::solver {

namespace {

// Row i's place among the solved rows (ascending), or -1 if it is not solved.
int pos_of(LdltPlan::Mask solved, unsigned i) {
  if (!(solved >> i & 1)) return -1;
  return mask_count(solved & ((LdltPlan::Mask{1} << i) - 1));
}

// The pattern of A's solved rows (ascending, `solved` as a set), as LdltPlan::analyse wants it:
// each row's non-zeros left of the diagonal, the other rows' columns dropped. Out of line: only
// new row sets need it, and inlined it costs solve_sparse's every call a little.
__attribute__((noinline)) void solved_pattern(const double* A, unsigned stride,
                                              const unsigned* rows, int nf, LdltPlan::Mask solved,
                                              LdltPlan::Mask* pattern) {
  using Mask = LdltPlan::Mask;
  constexpr unsigned kMax = LdltPlan::kMaxRows;
  if (stride == 1) {  // one row (dPAD(1) = 1): no row[1] to read in a pair
    pattern[0] = A[0] != 0.0 ? 1 : 0;
    return;
  }
  const __m128d zero = _mm_setzero_pd();
  const bool narrow = rows[nf - 1] < 64;  // every row set in one word (the rover on rocks)
  for (int a = 0; a < nf; ++a) {
    const unsigned i = rows[a];
    const double* row = A + i * stride;
    const auto pair = [&](unsigned j) {  // bits 0, 1: row[j], row[j + 1] non-zero
      return static_cast<std::uint64_t>(
          _mm_movemask_pd(_mm_cmpneq_pd(_mm_loadu_pd(row + j), zero)));
    };
    // Columns 0 .. i read in pairs (row[i + 1] exists: i is odd when stride == n), four at a
    // time where they lie within; then the other rows' columns dropped, top down.
    if (narrow) {  // the same steps on one word
      std::uint64_t m = 0;
      unsigned j = 0;
      for (; j + 3 <= i + 1; j += 4) m |= (pair(j) | pair(j + 2) << 2) << j;
      for (; j <= i; j += 2) m |= pair(j) << j;
      const std::uint64_t upto = i < 63 ? (std::uint64_t{2} << i) - 1 : ~std::uint64_t{0};
      m &= upto;
      for (std::uint64_t o = ~static_cast<std::uint64_t>(solved) & upto; o;) {
        const std::uint64_t below = (std::uint64_t{1} << (63 - __builtin_clzll(o))) - 1;
        m = (m & below) | ((m >> 1) & ~below);
        o &= below;
      }
      pattern[a] = m;
      continue;
    }
    Mask m = 0;
    for (unsigned base = 0; base <= i; base += 64) {  // each 64 in a word (no 128-bit shifts)
      const unsigned last = std::min(i, base + 63);
      std::uint64_t w = 0;
      unsigned j = base;
      for (; j + 3 <= last + 1; j += 4) w |= (pair(j) | pair(j + 2) << 2) << (j - base);
      for (; j <= last; j += 2) w |= pair(j) << (j - base);
      m |= Mask{w} << base;
    }
    const Mask upto = i < kMax - 1 ? (Mask{2} << i) - 1 : ~Mask{0};
    m &= upto;
    for (Mask o = ~solved & upto; o;) {
      const Mask below = (Mask{1} << mask_high(o)) - 1;
      m = (m & below) | ((m >> 1) & ~below);
      o &= below;
    }
    pattern[a] = m;
  }
}

// The solve with friction rows at their bounds (solve_sparse): on entry x holds y = A_SS⁻¹ b_S
// (rows[0..nf), factorised in ws.ldlt); on return x holds x_S and xf the clamped rows' forces
// s_i mu_i x_k(i). Returns false if the small system is singular or not finite.
bool solve_clamped(LcpWorkspace& ws, unsigned n, const double* A, unsigned stride,
                   const unsigned* rows, int nf, LdltPlan::Mask clamped, LdltPlan::Mask at_lo,
                   const double* pairslh, const int* findex, double* x, double* xf, int* pos) {
  constexpr int kMax = LdltPlan::kMaxRows;
  using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMax, kMax>;
  using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMax, 1>;
  const auto a_at = [&](unsigned i, unsigned j) {
    return i >= j ? A[i * stride + j] : A[j * stride + i];
  };
  for (unsigned i = 0; i < n; ++i) pos[i] = -1;
  for (int a = 0; a < nf; ++a) pos[rows[a]] = a;
  // x_i = s_i mu_i x_k for each clamped row i whose normal k is solved (a normal at zero makes
  // its friction zero): their forces enter the solved rows as columns of A times x_k, so each
  // normal gets one column, c_k = A_SS⁻¹ sum_i s_i mu_i A_Si (one solve per sliding contact,
  // not one per friction row: both rows of a pyramid slide at once in most rock contacts).
  // K: those normals' places.
  std::array<int, kMax> kpos, normal_of;
  int nk = 0, m = 0;
  std::array<unsigned, kMax> crow;
  std::array<double, kMax> scale;
  for (LdltPlan::Mask c = clamped; c; c &= c - 1) {
    const unsigned i = static_cast<unsigned>(mask_low(c));
    xf[i] = 0.0;
    const int pk = pos[findex[i]];
    if (pk < 0) continue;
    int q = 0;
    while (q < nk && kpos[q] != pk) ++q;
    if (q == nk) kpos[nk++] = pk;
    normal_of[m] = q;
    crow[m] = i;
    scale[m] = (at_lo >> i & 1 ? -1.0 : 1.0) * std::abs(pairslh[2 * i + 1]);
    ++m;
  }
  if (m == 0) return true;
  // The columns depend on A, the factor and the clamped rows' signs and mu only: a re-solve with
  // the kept factor (a new right-hand side, IslandStep::resolve) finds them as they were. The
  // factor's serial stands for A (a new A is factorised, which counts a new serial).
  LcpWorkspace::ClampedColumns& kept = ws.clamped;
  // (the same factor and clamped rows: the same solved normals, so the same m)
  bool same = kept.factor != 0 && kept.factor == ws.factors && kept.mask == clamped;
  for (int r = 0; same && r < m; ++r) same = kept.scale[r] == scale[r];
  if (!same) {
    for (int q = 0; q < nk; ++q) {
      double* cq = ws.clamped_cols.data() + q * kMax;
      for (int a = 0; a < nf; ++a) cq[a] = 0.0;
    }
    for (int r = 0; r < m; ++r) {  // (rows in ascending order: a fixed order of the sums)
      double* cq = ws.clamped_cols.data() + normal_of[r] * kMax;
      for (int a = 0; a < nf; ++a) cq[a] += a_at(rows[a], crow[r]) * scale[r];
    }
    ws.ldlt.solve_many(ws.clamped_cols.data(), nk, kMax);
    kept.factor = ws.factors;
    kept.mask = clamped;
    for (int r = 0; r < m; ++r) kept.scale[r] = scale[r];
  }
  // (I + G) x_K = y_K, G's column q the normals' entries of c_q
  Small g = Small::Identity(nk, nk);
  SmallVec yk(nk);
  for (int p = 0; p < nk; ++p) yk[p] = x[kpos[p]];
  for (int q = 0; q < nk; ++q) {
    const double* cq = ws.clamped_cols.data() + q * kMax;
    for (int p = 0; p < nk; ++p) g(p, q) += cq[kpos[p]];
  }
  const SmallVec xk = Eigen::PartialPivLU<Small>(g).solve(yk);
  if (!xk.allFinite()) return false;
  for (int q = 0; q < nk; ++q) {
    const double* cq = ws.clamped_cols.data() + q * kMax;
    const double xn = xk[q];
    for (int a = 0; a < nf; ++a) x[a] -= cq[a] * xn;
  }
  for (int r = 0; r < m; ++r) xf[crow[r]] = scale[r] * xk[normal_of[r]];
  return true;
}

}  // namespace

// The LCP as one linear system: the unbounded rows and the bounded rows guessed inside their
// bounds ("active") are solved together, every other bounded row sits at its zero bound
// (x = 0). Accepted only where Dantzig's method ends too (the solution is unique: A is
// positive definite): an active row's x within its bounds, an inactive row's w = A_i x - b_i
// on the side its zero bound allows (ODE's own test; a row with lo = hi = 0 is never checked,
// as in ODE). A wrong guess is flipped and the system solved again, kAttempts times at most.
// The guess starts from the last accepted one for the same bounded rows (LcpWorkspace::
// guesses). Returns false without touching the outputs if no guess held, if a row has bounds
// that depend on another's force (findex) and ws.coulomb_friction is off, a row has no zero
// bound, or there are over LdltPlan::kMaxRows (128) rows.
//
// Friction rows (findex[i] = k: |x_i| <= mu_i x_k, ODE's pyramid; with ws.coulomb_friction) are
// guessed too: inside (solved with the others, checked against mu_i times the final x_k) or at a
// bound, x_i = +-mu_i x_k, a linear relation with the normal force x_k that the solve must respect
// (seed 004 §3.4, Coulomb's law with the final normal force, as solve_coulomb (coulomb_lcp.cpp) for
// rigid ground). With y = A_SS⁻¹ b_S and c_i = A_SS⁻¹ A_Si for each friction row at a bound, x_S =
// y - sum_i c_i s_i mu_i x_k(i): the normal forces it involves solve a small dense system (I + G)
// x_K = y_K first. Checked as Dantzig's method ends: at +bound w_i <= 0, at -bound w_i >= 0.
bool solve_sparse(LcpWorkspace& ws, unsigned n, const double* A, double* pairsbx, double* outer_w,
                  unsigned nub, const double* pairslh, const int* findex,
                  std::uint64_t kept_factor) {
  using Mask = LdltPlan::Mask;
  constexpr int kMax = LdltPlan::kMaxRows;
  if (n > static_cast<unsigned>(kMax) || n == 0) return false;  // (row masks of kMax bits)
  Mask bounded = 0, friction = 0;
  for (unsigned i = 0; i < n; ++i) {
    const double lo = pairslh[2 * i], hi = pairslh[2 * i + 1];
    if (i < nub || ((!findex || findex[i] < 0) && lo == -dInfinity && hi == dInfinity)) continue;
    if (findex && findex[i] >= 0) {
      if (!ws.coulomb_friction || static_cast<unsigned>(findex[i]) >= n) return false;
      friction |= Mask{1} << i;
    } else if (lo != 0.0 && hi != 0.0) {
      return false;
    }
    bounded |= Mask{1} << i;
  }
  const int kAttempts = friction ? 5 : 3;
  const Mask all = n == kMax ? ~Mask{0} : (Mask{1} << n) - 1;
  const unsigned stride = dPAD(n);
  LcpWorkspace::Guess* memory = ws.guess_for(n, bounded);
  // Guessed inside their bounds: as last time for these rows; a new friction row sticks.
  Mask active = memory ? memory->active : friction;
  Mask at_lo = memory ? memory->at_lo : 0;  // friction rows at -mu x_k (the others at +)
  std::array<unsigned, kMax> rows;  // the solved rows: unbounded and active
  std::array<double, kMax> x, w;
  std::array<double, kMax> xf;  // every row's force (clamped friction rows included)
  std::array<int, kMax> pos;    // row -> its place in rows[], or -1
  Mask solved = 0;
  bool held = false;
  const auto a_at = [&](unsigned i, unsigned j) {  // ODE fills the lower triangle
    return i >= j ? A[i * stride + j] : A[j * stride + i];
  };
  for (int attempt = 0; attempt < kAttempts && !held; ++attempt) {
    solved = (all & ~bounded) | (active & bounded);
    int nf = 0;  // (word by word: a 128-bit mask's lowest bit costs more)
    for (auto m = static_cast<std::uint64_t>(solved); m; m &= m - 1)
      rows[nf++] = static_cast<unsigned>(__builtin_ctzll(m));
    for (auto m = static_cast<std::uint64_t>(solved >> 64); m; m &= m - 1)
      rows[nf++] = 64u + static_cast<unsigned>(__builtin_ctzll(m));
    const bool kept = kept_factor != 0 && kept_factor == ws.factors && n == ws.factored_n &&
                      solved == ws.factored;  // the factor of these rows of this A is in ldlt
    if (nf > 0 && kept) {
      for (int a = 0; a < nf; ++a) x[a] = pairsbx[2 * rows[a]];
      ws.ldlt.solve(x.data());
    } else if (nf > 0) {
      // A remembered plan for these rows serves if A has no non-zero outside its factor;
      // otherwise A's pattern makes or grows one.
      LdltPlan* known = ws.find(solved, nf, static_cast<int>(stride));
      const LdltPlan* plan = known;
      if (!known || !known->covers(A)) {
        std::array<Mask, kMax> pattern;
        solved_pattern(A, stride, rows.data(), nf, solved, pattern.data());
        plan = &ws.adopt(known, pattern.data(), rows.data(), nf, static_cast<int>(stride));
      }
      ++ws.factors;
      ws.factored = solved;
      ws.factored_n = n;
      if (!ws.ldlt.factor(*plan, A)) {
        ws.factored_n = 0;
        return false;
      }
      for (int a = 0; a < nf; ++a) x[a] = pairsbx[2 * rows[a]];
      ws.ldlt.solve(x.data());
    }
    const Mask clamped = friction & ~active;
    if (clamped && !solve_clamped(ws, n, A, stride, rows.data(), nf, clamped, at_lo, pairslh,
                                  findex, x.data(), xf.data(), pos.data()))
      return false;
    Mask wrong = 0;
    for (int a = 0; a < nf; ++a) {
      const unsigned i = rows[a];
      if (!std::isfinite(x[a])) return false;
      if (!(bounded >> i & 1)) continue;
      if (friction >> i & 1) {  // inside |x_i| <= mu_i x_k, x_k the final normal force
        const int pk = pos_of(solved, static_cast<unsigned>(findex[i]));
        const double bound = std::abs(pairslh[2 * i + 1]) * (pk >= 0 ? std::max(x[pk], 0.0) : 0.0);
        if (std::abs(x[a]) > bound) {
          wrong |= Mask{1} << i;
          at_lo = x[a] < 0.0 ? at_lo | (Mask{1} << i) : at_lo & ~(Mask{1} << i);
        }
        continue;
      }
      const double lo = pairslh[2 * i], hi = pairslh[2 * i + 1];
      if (x[a] < lo || x[a] > hi) wrong |= Mask{1} << i;
    }
    for (Mask m = bounded & ~solved; m; m &= m - 1) {
      // w_i = A_i x - b_i: A's row i left of the diagonal, its column i below (lower triangle),
      // in two interleaved sums (a single one waits an add latency per term).
      const unsigned i = static_cast<unsigned>(mask_low(m));
      const int split = mask_count(solved & ((Mask{1} << i) - 1));
      const double* row = A + i * stride;
      double s0 = 0.0, s1 = 0.0;
      int a = 0;
      for (; a + 1 < split; a += 2) {
        s0 += row[rows[a]] * x[a];
        s1 += row[rows[a + 1]] * x[a + 1];
      }
      if (a < split) {
        s0 += row[rows[a]] * x[a];
        ++a;
      }
      for (; a + 1 < nf; a += 2) {
        s0 += A[rows[a] * stride + i] * x[a];
        s1 += A[rows[a + 1] * stride + i] * x[a + 1];
      }
      if (a < nf) s0 += A[rows[a] * stride + i] * x[a];
      for (Mask c = clamped; c; c &= c - 1) {  // the friction rows at a bound
        const unsigned j = static_cast<unsigned>(mask_low(c));
        s1 += a_at(i, j) * xf[j];
      }
      const double wi = (s0 + s1) - pairsbx[2 * i];
      w[i] = wi;
      if (friction >> i & 1) {  // at +mu x_k: w <= 0; at -mu x_k: w >= 0; at 0 either side
        const bool lo_side = at_lo >> i & 1;
        if (xf[i] == 0.0) {
          at_lo = wi > 0.0 ? at_lo | (Mask{1} << i) : at_lo & ~(Mask{1} << i);
        } else if (lo_side ? wi < 0.0 : wi > 0.0) {
          wrong |= Mask{1} << i;  // pulled off its bound: inside
        }
        continue;
      }
      const double lo = pairslh[2 * i], hi = pairslh[2 * i + 1];
      if (!((lo == 0.0 && wi >= 0.0) || (hi == 0.0 && wi <= 0.0) || wi == 0.0)) wrong |= Mask{1} << i;
    }
    held = wrong == 0;
    active ^= wrong;
  }
  if (!held) return false;
  ws.remember(memory, n, bounded, solved & bounded, at_lo & friction & ~solved);
  for (unsigned i = 0; i < n; ++i) pairsbx[2 * i + 1] = 0.0;
  for (Mask c = friction & ~solved; c; c &= c - 1) {
    const unsigned i = static_cast<unsigned>(mask_low(c));
    pairsbx[2 * i + 1] = xf[i];
  }
  const int nf = mask_count(solved);  // (rows[] holds them)
  for (int a = 0; a < nf; ++a) pairsbx[2 * rows[a] + 1] = x[a];
  if (outer_w) {
    for (unsigned i = 0; i < n; ++i) outer_w[i] = (solved >> i & 1) ? 0.0 : w[i];
  }
  return true;
}

}  // namespace ernest::solver
