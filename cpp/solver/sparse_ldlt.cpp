// Sparse LDLᵀ (sparse_ldlt.hpp), the plan: minimum-degree order on bit masks, the factor's
// pattern, its supernodes and the lists the numeric part (sparse_ldlt_numeric.cpp) walks.
#include "ernest/solver/sparse_ldlt.hpp"

#include <algorithm>
#include <cstring>

#include "ernest/common/vector_math.hpp"

namespace ernest::solver {

namespace {
using Mask = LdltPlan::Mask;
inline Mask bit(int i) { return Mask{1} << i; }
inline int pop(Mask m) { return mask_count(m); }
inline int low(Mask m) { return mask_low(m); }
}  // namespace

bool LdltPlan::same_rows(const unsigned* rows, int n, int stride) const {
  if (n != n_ || stride != stride_) return false;
  for (int i = 0; i < n; ++i)
    if (rows[i] != rows_[i]) return false;
  return true;
}

// Also compiled for AVX2 (common/vector_math.hpp): 4 entries per comparison (GCC's generic
// vectors; two SSE2 halves in the baseline copy).
ERNEST_ALSO_AVX2
bool LdltPlan::covers(const double* a) {
  if (n_zeros_ < 0) list_zeros();
  typedef double V4 __attribute__((vector_size(32)));
  typedef long long M4 __attribute__((vector_size(32)));
  typedef double V2 __attribute__((vector_size(16)));
  typedef long long M2 __attribute__((vector_size(16)));
  M4 nonzero4 = {0, 0, 0, 0};
  M2 nonzero2 = {0, 0};
  bool nonzero1 = false;
  for (int g = 0; g < n_zeros_; ++g) {
    const double* p = a + zeros_[g].src;
    const int count = static_cast<int>(zeros_[g].count);
    int e = 0;
    for (; e + 4 <= count; e += 4) {  // (a NaN compares non-zero: not covered)
      V4 v;
      std::memcpy(&v, p + e, sizeof v);
      nonzero4 |= v != 0.0;
    }
    if (e + 2 <= count) {
      V2 v;
      std::memcpy(&v, p + e, sizeof v);
      nonzero2 |= v != 0.0;
      e += 2;
    }
    if (e < count) nonzero1 |= p[e] != 0.0;
  }
  return !nonzero1 && !(nonzero2[0] | nonzero2[1]) &&
         !(nonzero4[0] | nonzero4[1] | nonzero4[2] | nonzero4[3]);
}

bool LdltPlan::covers(const Mask* pattern) const {
  Mask outside = 0;
  for (int i = 0; i < n_; ++i) outside |= pattern[i] & ~filled_[i];
  return outside == 0;
}

namespace {
// Row sets as words: 64-bit when the rows fit (one instruction per bit operation), else Mask.
template <class W>
constexpr int kBits = static_cast<int>(8 * sizeof(W));
inline int word_low(std::uint64_t m) { return __builtin_ctzll(m); }
inline int word_low(Mask m) { return mask_low(m); }
inline int word_pop(std::uint64_t m) { return __builtin_popcountll(m); }
inline int word_pop(Mask m) { return mask_count(m); }
template <class W>
inline W word_bit(int i) { return W{1} << i; }
// Bits [0, i): the rows before row i (0 <= i <= kBits).
template <class W>
inline W before(int i) { return i == kBits<W> ? ~W{0} : word_bit<W>(i) - 1; }
// Bits [first, first + count) (count >= 1, first + count <= kBits).
template <class W>
inline W span(int first, int count) { return before<W>(count) << first; }
// Length of the run of set bits of m from bit `from` (< kBits) upwards (0 if that bit is clear).
template <class W>
inline int run_from(W m, int from) {
  const W rest = ~(m >> from);
  return rest ? word_low(rest) : kBits<W> - from;
}
}  // namespace

// Every step works on row sets (bit masks, in 64-bit words for up to 64 rows) and touches each
// non-zero of A and of L a few times, never every pair of rows: a new row set of a rock step is
// analysed while the step waits. Also compiled for AVX2 (common/vector_math.hpp), whose popcnt
// and tzcnt count rows in one instruction (integer work: the same plan).
ERNEST_ALSO_AVX2
void LdltPlan::analyse(const Mask* pattern, const unsigned* rows, int n, int stride) {
  n_ = n;
  stride_ = stride;
  w_stride_ = (n + 3) & ~3;
  std::uint64_t set[2] = {0, 0};  // the row set's words (no 128-bit shifts)
  for (int i = 0; i < n; ++i) {
    pattern_[i] = pattern[i];
    rows_[i] = rows[i];
    set[rows[i] >> 6 & 1] |= std::uint64_t{1} << (rows[i] & 63);
  }
  row_set_ = rows[n - 1] < kMaxRows ? set[0] | Mask{set[1]} << 64 : 0;
  const auto analyse_as = [&](auto word) __attribute__((always_inline)) {
    using W = decltype(word);
    const auto bit = [](int i) { return word_bit<W>(i); };
    const auto low = [](W m) { return word_low(m); };
    std::array<W, kMaxRows> adj;  // symmetric adjacency, each row its own neighbour
    for (int i = 0; i < n; ++i) adj[i] = static_cast<W>(pattern[i]) | bit(i);
    for (int i = 0; i < n; ++i)
      for (W m = static_cast<W>(pattern[i]) & before<W>(i); m; m &= m - 1) adj[low(m)] |= bit(i);
    // Minimum degree (ties: lowest row), eliminating on the masks; each eliminated row's live
    // neighbours are its column of L. Once the live rows form a clique they are the dense tail.
    // A row's degree changes only when it neighbours the eliminated row: kept, not recounted;
    // the live rows of each degree are a set (by_degree), so the lowest row of least degree is
    // found without a scan of all rows. (Degrees count the row itself: one less mask operation
    // per neighbour.)
    std::array<W, kMaxRows> column;  // L's column pattern, row numbering
    std::array<int, kMaxRows> degree;
    std::array<W, kMaxRows + 1> by_degree;
    for (int d = 0; d <= n; ++d) by_degree[d] = 0;
    for (int i = 0; i < n; ++i) {
      degree[i] = word_pop(adj[i]);
      by_degree[degree[i]] |= bit(i);
    }
    W alive = before<W>(n);
    int k = 0, least = 0;
    for (; k < n; ++k) {
      while (!by_degree[least]) ++least;
      const int best = low(by_degree[least]);
      if (least == n - k) break;  // every live row is adjacent to every other
      by_degree[least] &= ~bit(best);
      const W left = alive & ~bit(best);
      const W nb = adj[best] & left;
      for (W m = nb; m; m &= m - 1) {
        const int v = low(m);
        adj[v] |= nb;
        const int d = word_pop(adj[v] & left);
        if (d != degree[v]) {
          by_degree[degree[v]] &= ~bit(v);
          by_degree[d] |= bit(v);
          degree[v] = d;
          least = std::min(least, d);
        }
      }
      column[k] = nb;
      perm_[k] = static_cast<std::uint8_t>(best);
      alive = left;
    }
    dense_from_ = k;
    for (W m = alive; m; m &= m - 1) perm_[k++] = static_cast<std::uint8_t>(low(m));
    std::array<int, kMaxRows> pos;
    for (int p = 0; p < n; ++p) pos[perm_[p]] = p;
    // L + D's pattern (row numbering, lower) is the graph the elimination left in adj: A's
    // edges and the fill, each one an entry of the column of whichever end went first (the tail
    // a clique, or its rows' degrees would not have stopped the loop).
    for (int i = 0; i < n; ++i) filled_[i] = adj[i] & before<W>(i + 1);

    // Sparse columns as position lists (ascending), and L's rows (positions) as masks of their
    // sparse columns (for the copies).
    std::array<W, kMaxRows> row_cols;
    for (int r = 0; r < n; ++r) row_cols[r] = 0;
    int nr = 0;
    for (int c = 0; c < dense_from_; ++c) {
      col_start_[c] = static_cast<std::uint16_t>(nr);
      W below = 0;  // positions
      for (W m = column[c]; m; m &= m - 1) {
        const int r = pos[low(m)];
        below |= bit(r);
        row_cols[r] |= bit(c);
      }
      for (; below; below &= below - 1) col_rows_[nr++] = static_cast<std::uint8_t>(low(below));
    }
    col_start_[dense_from_] = static_cast<std::uint16_t>(nr);
    n_supers_ = 0;
    for (int c = 0; c < dense_from_;) {
      int w = 1;
      while (c + w < dense_from_) {  // does column c + w - 1 nest onto column c + w?
        const int a = c + w - 1, b = c + w;
        const int na = col_start_[a + 1] - col_start_[a], nb = col_start_[b + 1] - col_start_[b];
        if (na != nb + 1 || col_rows_[col_start_[a]] != b ||
            !std::equal(col_rows_.begin() + col_start_[a] + 1,
                        col_rows_.begin() + col_start_[a + 1], col_rows_.begin() + col_start_[b]))
          break;
        ++w;
      }
      supers_[n_supers_++] = Supernode{static_cast<std::uint8_t>(c), static_cast<std::uint8_t>(w)};
      c += w;
    }
    // What SparseLdlt::factor copies from A into the working matrix: each row's entries of the
    // factor (its sparse columns, then its diagonal or the tail up to it) in runs of consecutive
    // columns (runs in the working matrix; rows never join, w_stride_ >= n), each entry with its
    // own source in A (lower triangle: the larger row's).
    std::array<std::uint32_t, kMaxRows> row_at;  // A's row at each position
    for (int p = 0; p < n; ++p) row_at[p] = rows_[perm_[p]];
    n_fills_ = 0;
    int nsrc = 0;
    for (int r = 0; r < n; ++r) {
      const std::uint32_t i = row_at[r];
      W cols = row_cols[r] | (r < dense_from_ ? bit(r) : span<W>(dense_from_, r - dense_from_ + 1));
      while (cols) {
        const int first = low(cols), count = run_from(cols, first);
        fills_[n_fills_++] = Fill{static_cast<std::uint16_t>(nsrc),
                                  static_cast<std::uint16_t>(r * w_stride_ + first),
                                  static_cast<std::uint16_t>(count)};
        std::uint32_t* src = fill_src_.data() + nsrc;
        for (int e = 0; e < count; ++e) {
          const std::uint32_t j = row_at[first + e];
          src[e] = std::max(i, j) * stride + std::min(i, j);
        }
        nsrc += count;
        cols &= ~span<W>(first, count);
      }
    }
  };
  if (n <= 64)
    analyse_as(std::uint64_t{0});
  else
    analyse_as(Mask{0});
  n_zeros_ = -1;  // listed when first needed (covers(a))
}

// A's entries outside the factor's pattern, in runs consecutive in A: runs of zero bits along a
// row whose rows are consecutive in A (next_row), joined to the run before where they continue
// it. Only covers(a) reads them, and most new plans on rocks are replaced before they are
// checked: listed on the first check, not by analyse. Also compiled for AVX2 (tzcnt).
ERNEST_ALSO_AVX2
void LdltPlan::list_zeros() {
  const auto list_as = [&](auto word) __attribute__((always_inline)) {
    using W = decltype(word);
    constexpr int bits = kBits<W>;
    const auto bit = [](int i) { return word_bit<W>(i); };
    const auto low = [](W m) { return word_low(m); };
    W next_row = 0;  // bit j: rows_[j] == rows_[j - 1] + 1
    for (int j = 1; j < n_; ++j)
      if (rows_[j] == rows_[j - 1] + 1) next_row |= bit(j);
    n_zeros_ = 0;
    std::uint32_t zeros_end = 0;  // one past the last run
    for (int i = 0; i < n_; ++i) {
      const W outside = static_cast<W>(~filled_[i]) & before<W>(i + 1);
      const W joined = outside & next_row;
      for (W m = outside; m;) {
        const int j = low(m), count = j + 1 < bits ? 1 + run_from(joined, j + 1) : 1;
        const std::uint32_t src = rows_[i] * stride_ + rows_[j];
        if (n_zeros_ > 0 && zeros_end == src)
          zeros_[n_zeros_ - 1].count += count;
        else
          zeros_[n_zeros_++] = Zeros{src, static_cast<std::uint32_t>(count)};
        zeros_end = src + count;
        m &= ~span<W>(j, count);
      }
    }
  };
  if (n_ <= 64)
    list_as(std::uint64_t{0});
  else
    list_as(Mask{0});
}

}  // namespace ernest::solver
