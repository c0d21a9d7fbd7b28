// Sparse LDLᵀ for the constraint systems of one rigid-body step (up to 128 rows). ODE factorises
// J M⁻¹ Jᵀ densely; for a tree of bodies most of it is zero (rows couple only through a shared
// body), and in a minimum-degree order the factor stays sparse up to a small dense tail.
#pragma once

#include <array>
#include <cstdint>

namespace ernest::solver {

/// Symbolic analysis of one sparsity pattern: minimum-degree order, the pattern of the factor,
/// and the trailing clique that is factorised densely. A pure function of the pattern: the
/// rounding of a factorisation depends on the plan, so a caller wanting bit-exact repeats must
/// choose plans reproducibly (lcp_workspace.hpp keeps their patterns in the snapshot).
class LdltPlan {
 public:
  /// The rover's ~50 rows, and 12 more per wheel on a rock (4 collision points x 3 rows): two
  /// or more wheels on rocks exceed 64 rows, so row sets are 128-bit masks (GCC's unsigned
  /// __int128: two words in registers, no allocation). Larger problems go to ODE's solver.
  static constexpr int kMaxRows = 128;
  using Mask = unsigned __int128;

  /// Rows of the system: A(i, j) = a[rows[i] * stride + rows[j]] for i >= j (lower triangle of
  /// a larger matrix, ODE's layout); pattern[i] has bit j set where that entry is non-zero
  /// (j <= i, diagonal included). 1 <= n <= kMaxRows, rows ascending.
  void analyse(const Mask* pattern, const unsigned* rows, int n, int stride);
  /// Whether this plan was made for these rows and stride.
  bool same_rows(const unsigned* rows, int n, int stride) const;
  /// Its rows as a set (bit r: row r), 0 if a row is kMaxRows or more.
  Mask row_set() const { return row_set_; }
  /// Whether a matrix with this pattern (same rows) can be factorised with this plan: every
  /// non-zero lies in the pattern of the factor.
  bool covers(const Mask* pattern) const;
  /// The same asked of A itself (same rows and stride): every entry outside the factor's
  /// pattern is zero. Reads only those entries (listed on the first call: not const).
  bool covers(const double* a);
  int size() const { return n_; }
  int stride() const { return stride_; }
  const unsigned* rows() const { return rows_.data(); }
  /// The pattern the plan was analysed from.
  const Mask* pattern() const { return pattern_.data(); }
  /// Columns [dense_from(), size()) are one clique, factorised densely.
  int dense_from() const { return dense_from_; }

 private:
  friend class SparseLdlt;
  void list_zeros();
  int n_ = 0, stride_ = 0, dense_from_ = 0, w_stride_ = 0;
  Mask row_set_ = 0;
  std::array<Mask, kMaxRows> pattern_{};
  std::array<Mask, kMaxRows> filled_{};  // pattern of L + D (lower), row numbering
  std::array<unsigned, kMaxRows> rows_{};
  std::array<std::uint8_t, kMaxRows> perm_{};  // position k of the order holds row perm_[k]
  // Below-diagonal rows (positions) of each sparse column k < dense_from_, ascending.
  std::array<std::uint16_t, kMaxRows + 1> col_start_{};
  std::array<std::uint8_t, kMaxRows * kMaxRows / 2> col_rows_{};
  // Supernodes among the sparse columns: consecutive columns whose patterns nest (column k's is
  // k + 1 and column k + 1's), so that they share the rows below the last one. Width 1 = a lone
  // column.
  struct Supernode {
    std::uint8_t first, width;
  };
  int n_supers_ = 0;
  std::array<Supernode, kMaxRows> supers_{};
  // The entries of A outside the factor's pattern, in runs consecutive in A (covers(a)).
  struct Zeros {
    std::uint32_t src, count;
  };
  int n_zeros_ = -1;  // -1: not listed yet (list_zeros)
  std::array<Zeros, kMaxRows * (kMaxRows + 1) / 2> zeros_{};
  // The entries of the factor's pattern, copied from A into the working matrix (SparseLdlt::
  // factor) in runs contiguous in the working matrix, each entry's source in fill_src_ (from
  // first on).
  struct Fill {
    std::uint16_t first, dst, count;
  };
  int n_fills_ = 0;
  std::array<Fill, kMaxRows * (kMaxRows + 1) / 2> fills_{};
  std::array<std::uint32_t, kMaxRows * (kMaxRows + 1) / 2> fill_src_{};
};

/// Rows in a row set; the lowest and the highest row of a non-empty one.
inline int mask_count(LdltPlan::Mask m) {
  return __builtin_popcountll(static_cast<std::uint64_t>(m)) +
         __builtin_popcountll(static_cast<std::uint64_t>(m >> 64));
}
inline int mask_low(LdltPlan::Mask m) {
  const auto lo = static_cast<std::uint64_t>(m);
  return lo ? __builtin_ctzll(lo) : 64 + __builtin_ctzll(static_cast<std::uint64_t>(m >> 64));
}
inline int mask_high(LdltPlan::Mask m) {
  const auto hi = static_cast<std::uint64_t>(m >> 64);
  return hi ? 127 - __builtin_clzll(hi) : 63 - __builtin_clzll(static_cast<std::uint64_t>(m));
}

/// Numeric factorisation with a plan; working data preallocated (never allocates).
class SparseLdlt {
 public:
  /// Factorises A (see LdltPlan::analyse) in the plan's order. Returns false if a pivot is not
  /// positive and finite (A not positive definite): nothing usable is left then.
  bool factor(const LdltPlan& plan, const double* a);
  /// x := A⁻¹ x, x in the numbering of the plan's rows (x[i] belongs to rows[i]).
  void solve(double* x) const;
  /// solve() of k right-hand sides, column c at x + c * stride: the same bits as k solve() calls,
  /// faster (up to four solves interleaved: their latency-bound chains overlap).
  void solve_many(double* x, int k, int stride) const;

 private:
  template <int K>
  void solve_k(double* const* xs) const;
  bool factor_column(int k);
  bool factor_supernode(int k0, int width);
  static void fill(const LdltPlan& plan, const double* a, double* w);
  const LdltPlan* plan_ = nullptr;
  alignas(64) std::array<double, LdltPlan::kMaxRows * LdltPlan::kMaxRows> w_{};  // L, row-major
  std::array<double, LdltPlan::kMaxRows * LdltPlan::kMaxRows / 2> lcol_{};  // sparse columns of L
  std::array<double, LdltPlan::kMaxRows> dinv_{};  // 1 / D
  // d_c L_rc of the rows below a supernode, over its columns (row stride kMaxRows)
  alignas(16) std::array<double, LdltPlan::kMaxRows * LdltPlan::kMaxRows> e_{};
};

}  // namespace ernest::solver
