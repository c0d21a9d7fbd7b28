// SparseLdlt (sparse_ldlt.hpp), the numeric part: the plan's sparse columns right-looking (lone
// columns entry by entry), supernodes and the trailing clique through one dense kernel
// (dense_ldlt; ODE's dFactorLDLT and dSolveL1 cost 1.3x as many instructions at the rover's
// sizes), and the solves. The plan (order, patterns, copy lists) is sparse_ldlt.cpp.
#include "ernest/solver/sparse_ldlt.hpp"

#include <emmintrin.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "ernest/common/vector_math.hpp"

namespace ernest::solver {

namespace {
// Supernodes at least this wide are factorised with the dense kernel (factor_supernode).
constexpr int kDenseSupernode = 4;

// Sum of the products of n pairs in four interleaved partial sums: a single running sum would
// wait a full add latency per term (the fixed order keeps results bit-repeatable).
template <class Term>
inline double sum4(int n, Term term) {
  double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    s0 += term(i);
    s1 += term(i + 1);
    s2 += term(i + 2);
    s3 += term(i + 3);
  }
  for (; i < n; ++i) s0 += term(i);
  return (s0 + s1) + (s2 + s3);
}

// GCC's generic vectors (AVX2 registers in the AVX2 copies, SSE2 pairs in the others). Their
// unaligned loads and stores go through memcpy (one instruction).
typedef double V4 __attribute__((vector_size(32)));
typedef double V2 __attribute__((vector_size(16)));

// sum4 of a[i] b[i] with explicit vectors (the 4 partial sums one vector: the same bits).
inline double dot(const double* a, const double* b, int n) {
  V4 acc = {0.0, 0.0, 0.0, 0.0};
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    V4 va, vb;
    std::memcpy(&va, a + i, sizeof va);
    std::memcpy(&vb, b + i, sizeof vb);
    acc += va * vb;
  }
  double s0 = acc[0];
  for (; i < n; ++i) s0 += a[i] * b[i];
  return (s0 + acc[1]) + (acc[2] + acc[3]);
}

// r[0 .. size of V) -= l[0] u0 + l[1] u1 + l[2] u2 + l[3] u3, term by term (V: 2 or 4 doubles).
template <class V>
inline void sub_columns(double* r, const double* u0, const double* u1, const double* u2,
                        const double* u3, const double* l) {
  V vr, a0, a1, a2, a3;
  std::memcpy(&vr, r, sizeof vr);
  std::memcpy(&a0, u0, sizeof vr);
  std::memcpy(&a1, u1, sizeof vr);
  std::memcpy(&a2, u2, sizeof vr);
  std::memcpy(&a3, u3, sizeof vr);
  vr = (((vr - l[0] * a0) - l[1] * a1) - l[2] * a2) - l[3] * a3;
  std::memcpy(r, &vr, sizeof vr);
}

// y[i] -= l[i] c for i < n: 4, then 2, then 1 at a time (short rows: no loop versioning).
inline void sub_scaled(double* y, const double* l, double c, int n) {
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    V4 vy, vl;
    std::memcpy(&vy, y + i, sizeof vy);
    std::memcpy(&vl, l + i, sizeof vl);
    vy -= vl * c;
    std::memcpy(y + i, &vy, sizeof vy);
  }
  if (i + 2 <= n) {
    V2 vy, vl;
    std::memcpy(&vy, y + i, sizeof vy);
    std::memcpy(&vl, l + i, sizeof vl);
    vy -= vl * c;
    std::memcpy(y + i, &vy, sizeof vy);
    i += 2;
  }
  if (i < n) y[i] -= l[i] * c;
}
}  // namespace

// Column k alone (pivot d_k): updates the entries of its pattern only, entry by entry (the lone
// columns are short: 1 to 9 rows), right-looking.
bool SparseLdlt::factor_column(int k) {
  const LdltPlan& plan = *plan_;
  double* w = w_.data();
  const int s = plan.w_stride_;
  const double d = w[k * s + k];
  if (!(d > 0.0) || !std::isfinite(d)) return false;
  const double inv = 1.0 / d;
  dinv_[k] = inv;
  const int q0 = plan.col_start_[k], m = plan.col_start_[k + 1] - q0;
  const std::uint8_t* rows = plan.col_rows_.data() + q0;
  double t[LdltPlan::kMaxRows];  // column k (d_k L_rk), by place in the column
  for (int a = 0; a < m; ++a) t[a] = w[rows[a] * s + k];
  for (int a = 0; a < m; ++a) {
    double* wr = w + rows[a] * s;
    const double l = t[a] * inv;
    for (int b = 0; b <= a; ++b) wr[rows[b]] -= l * t[b];
    wr[k] = l;
    lcol_[q0 + a] = l;
  }
  return true;
}

namespace {
// Dense LDLᵀ of a trapezoid of rows (each at its own address: a supernode's rows below it are
// scattered): rows 0 .. width - 1 a square block with its diagonal at row[i][i], rows width ..
// nrows - 1 below it, entries row[i][0 .. min(i, width - 1)] (the lower part; nothing else is
// read or written). On return row[i][j] = L_ij below the diagonal, dinv[j] = 1 / d_j, and for
// the rows below (if e), e[(i - width) * ke + j] = d_j L_ij; if lc, also L by columns, column j
// at lc[j * nrows - j (j + 1) / 2], rows j + 1 .. nrows - 1 (a supernode's columns as
// SparseLdlt::lcol_ holds them). Right-looking in blocks of 4
// columns, row by row: a row's 4 entries in the block are eliminated in registers (t_ic = d_c
// L_ic, kept by column in u for the rows after it), then the row right of the block updated by
// all 4 at once, vectorised over contiguous u. Each entry sees the operations of column-by-column
// elimination in the same order (a product, then a difference, column by column), so the AVX2
// and baseline copies give the same bits. False if a pivot is not positive and finite.
ERNEST_ALSO_AVX2
bool dense_ldlt(double* const* row, int nrows, int width, double* dinv, double* e, int ke,
                double* lc) {
  alignas(32) double u[4][LdltPlan::kMaxRows];  // t_ic of the block's columns, by row
  for (int k = 0; k < width; k += 4) {
    const int kb = std::min(4, width - k);
    double* lcb[4] = {};  // the block's columns of L in lc, row i at [i]
    for (int c = 0; lc != nullptr && c < kb; ++c) {
      const int j = k + c;
      lcb[c] = lc + (j * nrows - j * (j + 1) / 2 - j - 1);
    }
    // The block's own rows: their entries left of the diagonal, then the pivot.
    for (int i = k; i < k + kb; ++i) {  // (unrolled: row i has i - k entries left of its pivot)
      double* __restrict ri = row[i];
      double d = ri[i], l0 = 0.0, l1 = 0.0;
      if (i > k) {
        const double t0 = ri[k];
        l0 = t0 * dinv[k];
        u[0][i] = t0, ri[k] = l0;
        d -= l0 * t0;
      }
      if (i > k + 1) {
        const double t1 = ri[k + 1] - l0 * u[0][k + 1];
        l1 = t1 * dinv[k + 1];
        u[1][i] = t1, ri[k + 1] = l1;
        d -= l1 * t1;
      }
      if (i > k + 2) {
        const double t2 = (ri[k + 2] - l0 * u[0][k + 2]) - l1 * u[1][k + 2];
        const double l2 = t2 * dinv[k + 2];
        u[2][i] = t2, ri[k + 2] = l2;
        d -= l2 * t2;
      }
      if (lc != nullptr)
        for (int c = k; c < i; ++c) lcb[c - k][i] = ri[c];
      const double inv = 1.0 / d;
      if (!(inv > 0.0) || !std::isfinite(inv)) return false;
      dinv[i] = inv;
    }
    const double* __restrict u0 = u[0];
    const double* __restrict u1 = u[1];
    const double* __restrict u2 = u[2];
    const double* __restrict u3 = u[3];
    double *lc0 = lcb[0], *lc1 = lcb[1], *lc2 = lcb[2], *lc3 = lcb[3];
    for (int i = k + kb; i < nrows; ++i) {
      double* __restrict ri = row[i];
      if (kb < 4) {  // the last block: nothing right of it
        double l[4];
        for (int c = k; c < k + kb; ++c) {
          double t = ri[c];
          for (int p = k; p < c; ++p) t -= l[p - k] * u[p - k][c];
          u[c - k][i] = t;
          l[c - k] = t * dinv[c];
          ri[c] = l[c - k];
          if (lc != nullptr) lcb[c - k][i] = l[c - k];
          if (e != nullptr && i >= width) e[(i - width) * ke + c] = t;
        }
        continue;
      }
      const double t0 = ri[k];
      const double l0 = t0 * dinv[k];
      const double t1 = ri[k + 1] - l0 * u0[k + 1];
      const double l1 = t1 * dinv[k + 1];
      const double t2 = (ri[k + 2] - l0 * u0[k + 2]) - l1 * u1[k + 2];
      const double l2 = t2 * dinv[k + 2];
      const double t3 = ((ri[k + 3] - l0 * u0[k + 3]) - l1 * u1[k + 3]) - l2 * u2[k + 3];
      const double l3 = t3 * dinv[k + 3];
      const double l[4] = {l0, l1, l2, l3};
      u[0][i] = t0, u[1][i] = t1, u[2][i] = t2, u[3][i] = t3;
      ri[k] = l0, ri[k + 1] = l1, ri[k + 2] = l2, ri[k + 3] = l3;
      if (lc0 != nullptr) lc0[i] = l0, lc1[i] = l1, lc2[i] = l2, lc3[i] = l3;
      if (e != nullptr && i >= width) {
        double* ei = e + (i - width) * ke + k;
        ei[0] = t0, ei[1] = t1, ei[2] = t2, ei[3] = t3;
      }
      // The rest of the row, 4 entries at a time, then 2, then 1 (explicit vectors: no loop
      // versioning for these short rows).
      const int end = std::min(i, width - 1) + 1;
      int j = k + 4;
      for (; j + 4 <= end; j += 4) sub_columns<V4>(ri + j, u0 + j, u1 + j, u2 + j, u3 + j, l);
      if (j + 2 <= end) sub_columns<V2>(ri + j, u0 + j, u1 + j, u2 + j, u3 + j, l), j += 2;
      if (j < end) ri[j] = (((ri[j] - l0 * u0[j]) - l1 * u1[j]) - l2 * u2[j]) - l3 * u3[j];
    }
  }
  return true;
}
}  // namespace

// Columns k0 .. k0 + width - 1 whose patterns nest share the rows R below them: the block and
// R factorised as one dense trapezoid (dense_ldlt: L, also into lcol_ for the solves, and
// d_c L_rc of R into e_), then R x R updated once, entry by entry with dot products over the
// block's columns. Also compiled for AVX2 (those dot products 4 wide; the same bits).
ERNEST_ALSO_AVX2
bool SparseLdlt::factor_supernode(int k0, int width) {
  const LdltPlan& plan = *plan_;
  double* w = w_.data();
  const int s = plan.w_stride_, k1 = k0 + width - 1;
  constexpr int ke = LdltPlan::kMaxRows;
  const std::uint8_t* below = plan.col_rows_.data() + plan.col_start_[k1];
  const int m = plan.col_start_[k1 + 1] - plan.col_start_[k1];
  std::array<double*, LdltPlan::kMaxRows> rows;
  for (int i = 0; i < width; ++i) rows[i] = w + (k0 + i) * s + k0;
  for (int a = 0; a < m; ++a) rows[width + a] = w + below[a] * s + k0;
  double* e = e_.data();
  if (!dense_ldlt(rows.data(), width + m, width, dinv_.data() + k0, e, ke,
                  lcol_.data() + plan.col_start_[k0]))
    return false;
  for (int a = 0; a < m; ++a) {
    double* wr = w + below[a] * s;
    const double* la = wr + k0;
    for (int b = 0; b <= a; ++b) {
      const double* eb = e + b * ke;
      wr[below[b]] -= sum4(width, [&](int c) { return la[c] * eb[c]; });
    }
  }
  return true;
}

// The entries of the factor's pattern from A into the working matrix w (LdltPlan::fills_), two
// at a time (one store).
void SparseLdlt::fill(const LdltPlan& plan, const double* __restrict a, double* __restrict w) {
  for (int g = 0; g < plan.n_fills_; ++g) {
    const LdltPlan::Fill& f = plan.fills_[g];
    const std::uint32_t* __restrict src = plan.fill_src_.data() + f.first;
    double* __restrict dst = w + f.dst;
    int e = 0;
    for (; e + 2 <= f.count; e += 2)  // (SSE2 by hand: GCC's vectorised form costs more)
      _mm_storeu_pd(dst + e, _mm_loadh_pd(_mm_load_sd(a + src[e]), a + src[e + 1]));
    if (e < f.count) dst[e] = a[src[e]];
  }
}

bool SparseLdlt::factor(const LdltPlan& plan, const double* a) {
  plan_ = &plan;
  double* w = w_.data();
  const int s = plan.w_stride_, n = plan.n_, df = plan.dense_from_;
  fill(plan, a, w);
  // Right-looking from supernode to supernode (lone columns one by one), then the dense tail.
  for (int sn = 0; sn < plan.n_supers_; ++sn) {
    const int k = plan.supers_[sn].first;
    if (plan.supers_[sn].width >= kDenseSupernode) {
      if (!factor_supernode(k, plan.supers_[sn].width)) return false;
      continue;
    }
    for (int kk = k; kk < k + plan.supers_[sn].width; ++kk)
      if (!factor_column(kk)) return false;
  }
  if (df == n) return true;
  std::array<double*, LdltPlan::kMaxRows> rows;
  for (int i = df; i < n; ++i) rows[i - df] = w + i * s + df;
  return dense_ldlt(rows.data(), n - df, n - df, dinv_.data() + df, nullptr, 0, nullptr);
}

// x_c := A⁻¹ x_c for the K right-hand sides xs[0 .. K). Every column sees the operations of a
// solve of its own in the same order (the same bits as K separate solves); interleaved, their
// dependency chains (the triangular solves are latency bound) overlap. Inlined into solve() and
// solve_many(), which are compiled for AVX2 too (common/vector_math.hpp; the same bits).
template <int K>
__attribute__((always_inline)) inline void SparseLdlt::solve_k(double* const* xs) const {
  const LdltPlan& plan = *plan_;
  const double* __restrict w = w_.data();
  const double* __restrict lc = lcol_.data();
  const std::uint8_t* __restrict cr = plan.col_rows_.data();
  const int s = plan.w_stride_, n = plan.n_, df = plan.dense_from_;
  alignas(32) double ys[K][LdltPlan::kMaxRows];
  for (int r = 0; r < K; ++r)
    for (int p = 0; p < n; ++p) ys[r][p] = xs[r][plan.perm_[p]];
  const std::uint16_t* cs = plan.col_start_.data();
  // A supernode's columns (k0 .. k1, nested: column c's rows are c + 1 .. k1, then the rows
  // below k1) are contiguous slices of one vector z = (y[k0 + 1 .. k1], y[below]): column c's
  // is z[c - k0 ..]. The solves run over z without row indices, each entry seeing the same
  // operations in the same order as over y (the same bits).
  alignas(32) double zs[K][LdltPlan::kMaxRows];
  const auto gather = [&](int k0, int k1) {
    const int nb = k1 - k0, m = cs[k1 + 1] - cs[k1];
    for (int r = 0; r < K; ++r) {
      for (int i = 0; i < nb; ++i) zs[r][i] = ys[r][k0 + 1 + i];
      for (int i = 0; i < m; ++i) zs[r][nb + i] = ys[r][cr[cs[k1] + i]];
    }
    return nb + m;
  };
  const auto scatter = [&](int k0, int k1, int len) {
    const int nb = k1 - k0;
    for (int r = 0; r < K; ++r) {
      for (int i = 0; i < nb; ++i) ys[r][k0 + 1 + i] = zs[r][i];
      for (int i = nb; i < len; ++i) ys[r][cr[cs[k1] + i - nb]] = zs[r][i];
    }
  };
  // L z = x: sparse columns (lone columns by row index, supernodes over z), then the dense
  // tail by rows.
  for (int sn = 0; sn < plan.n_supers_; ++sn) {
    const int k0 = plan.supers_[sn].first, k1 = k0 + plan.supers_[sn].width - 1;
    if (k0 == k1) {
      for (int r = 0; r < K; ++r) {
        double* y = ys[r];
        const double yk = y[k0];
        for (int q = cs[k0]; q < cs[k0 + 1]; ++q) y[cr[q]] -= lc[q] * yk;
      }
      continue;
    }
    const int len = gather(k0, k1);
    for (int c = k0; c <= k1; ++c) {
      const double* l = lc + cs[c];
      for (int r = 0; r < K; ++r) {
        const double yc = c == k0 ? ys[r][k0] : zs[r][c - k0 - 1];
        sub_scaled(zs[r] + (c - k0), l, yc, len - (c - k0));
      }
    }
    scatter(k0, k1, len);
  }
  for (int i = df + 1; i < n; ++i) {
    const double* wi = w + i * s + df;
    for (int r = 0; r < K; ++r) ys[r][i] -= dot(wi, ys[r] + df, i - df);
  }
  for (int r = 0; r < K; ++r)
    for (int k = 0; k < n; ++k) ys[r][k] *= dinv_[k];
  // Lᵀ x = z: the dense tail by rows (bottom up), then the sparse columns.
  for (int i = n - 1; i > df; --i) {
    const double* wi = w + i * s;
    for (int r = 0; r < K; ++r) sub_scaled(ys[r] + df, wi + df, ys[r][i], i - df);
  }
  for (int sn = plan.n_supers_ - 1; sn >= 0; --sn) {
    const int k0 = plan.supers_[sn].first, k1 = k0 + plan.supers_[sn].width - 1;
    if (k0 == k1) {
      const int q0 = cs[k0];
      for (int r = 0; r < K; ++r) {
        double* y = ys[r];
        y[k0] -= sum4(cs[k0 + 1] - q0, [&](int q) { return lc[q0 + q] * y[cr[q0 + q]]; });
      }
      continue;
    }
    const int len = gather(k0, k1);
    for (int c = k1; c >= k0; --c) {
      const double* l = lc + cs[c];
      for (int r = 0; r < K; ++r) {
        const double yc = ys[r][c] - dot(l, zs[r] + (c - k0), len - (c - k0));
        ys[r][c] = yc;
        if (c > k0) zs[r][c - k0 - 1] = yc;
      }
    }
  }
  for (int r = 0; r < K; ++r)
    for (int p = 0; p < n; ++p) xs[r][plan.perm_[p]] = ys[r][p];
}

ERNEST_ALSO_AVX2
void SparseLdlt::solve(double* x) const { solve_k<1>(&x); }

ERNEST_ALSO_AVX2
void SparseLdlt::solve_many(double* x, int k, int stride) const {
  double* cols[4];
  for (int c = 0; c < k;) {
    const int now = std::min(4, k - c);
    for (int r = 0; r < now; ++r) cols[r] = x + (c + r) * stride;
    switch (now) {
      case 4: solve_k<4>(cols); break;
      case 3: solve_k<3>(cols); break;
      case 2: solve_k<2>(cols); break;
      default: solve_k<1>(cols); break;
    }
    c += now;
  }
}

}  // namespace ernest::solver
