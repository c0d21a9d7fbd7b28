// Sparse LDLᵀ (sparse_ldlt.hpp), the plan: minimum-degree order on bit masks, the factor's
// pattern, its supernodes and the lists the numeric part (sparse_ldlt_numeric.cpp) walks.
#include "ernest/dynamics/sparse_ldlt.hpp"

#include <algorithm>
#include <cstring>

#include "ernest/common/vector_math.hpp"

namespace ernest::dynamics {

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
bool LdltPlan::covers(const double* a) const {
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

void LdltPlan::analyse(const Mask* pattern, const unsigned* rows, int n, int stride) {
  n_ = n;
  stride_ = stride;
  w_stride_ = (n + 3) & ~3;
  for (int i = 0; i < n; ++i) {
    pattern_[i] = pattern[i];
    rows_[i] = rows[i];
  }
  // Symmetric adjacency without the diagonal.
  std::array<Mask, kMaxRows> adj{};
  for (int i = 0; i < n; ++i) {
    Mask m = pattern[i] & ~bit(i);
    while (m) {
      const int j = low(m);
      m &= m - 1;
      adj[i] |= bit(j);
      adj[j] |= bit(i);
    }
  }
  // Minimum degree (ties: lowest row), eliminating on the masks; each eliminated row's live
  // neighbours are its column of L. Once the live rows form a clique they are the dense tail.
  // A row's degree changes only when it neighbours the eliminated row: kept, not recounted.
  std::array<Mask, kMaxRows> column{};  // L's column pattern, row numbering
  std::array<int, kMaxRows> degree;
  for (int i = 0; i < n; ++i) degree[i] = pop(adj[i]);
  Mask alive = n == kMaxRows ? ~Mask{0} : bit(n) - 1;
  int k = 0;
  for (; k < n; ++k) {
    int best = -1, best_degree = kMaxRows;
    for (Mask m = alive; m; m &= m - 1) {
      const int v = low(m);
      if (degree[v] < best_degree) best_degree = degree[v], best = v;
    }
    if (best_degree == n - k - 1) break;  // every live row is adjacent to every other
    const Mask nb = adj[best] & alive;
    const Mask left = alive & ~bit(best);
    for (Mask m = nb; m; m &= m - 1) {
      const int v = low(m);
      adj[v] |= nb & ~bit(v);
      degree[v] = pop(adj[v] & left);
    }
    column[k] = nb;
    perm_[k] = static_cast<std::uint8_t>(best);
    alive &= ~bit(best);
  }
  dense_from_ = k;
  for (Mask m = alive; m; m &= m - 1) perm_[k++] = static_cast<std::uint8_t>(low(m));
  std::array<int, kMaxRows> pos{};
  for (int p = 0; p < n; ++p) pos[perm_[p]] = p;
  for (int i = 0; i < n; ++i) filled_[i] = bit(i);
  const auto fill = [&](int i, int j) { filled_[std::max(i, j)] |= bit(std::min(i, j)); };
  for (int c = 0; c < dense_from_; ++c)
    for (Mask m = column[c]; m; m &= m - 1) fill(perm_[c], low(m));
  for (int r = dense_from_; r < n; ++r)
    for (int c = dense_from_; c < r; ++c) fill(perm_[r], perm_[c]);

  // Sparse columns as position lists (ascending) and runs; the entries of L's pattern to copy.
  int nr = 0, nruns = 0;
  n_copies_ = 0;
  std::array<Mask, kMaxRows> below_of;  // positions below the diagonal in each sparse column
  const auto copy = [&](int r, int c) {  // positions r >= c
    const unsigned i = rows_[perm_[r]], j = rows_[perm_[c]];
    const std::uint32_t src = i >= j ? i * stride + j : j * stride + i;
    const auto dst = static_cast<std::uint16_t>(r * w_stride_ + c);
    if (n_copies_ > 0) {
      Copy& last = copies_[n_copies_ - 1];
      if (last.dst + last.count == dst && last.src + last.count == src) {
        ++last.count;
        return;
      }
    }
    copies_[n_copies_++] = Copy{src, dst, 1};
  };
  for (int c = 0; c < dense_from_; ++c) {
    col_start_[c] = static_cast<std::uint16_t>(nr);
    run_start_[c] = static_cast<std::uint16_t>(nruns);
    Mask below = 0;  // positions
    for (Mask m = column[c]; m; m &= m - 1) below |= bit(pos[low(m)]);
    below_of[c] = below;
    for (Mask m = below; m; m &= m - 1) {
      const int r = low(m);
      col_rows_[nr++] = static_cast<std::uint8_t>(r);
      if (nruns > run_start_[c] && runs_[nruns - 1].first + runs_[nruns - 1].count == r)
        ++runs_[nruns - 1].count;
      else
        runs_[nruns++] = Run{static_cast<std::uint8_t>(r), 1};
    }
  }
  col_start_[dense_from_] = static_cast<std::uint16_t>(nr);
  run_start_[dense_from_] = static_cast<std::uint16_t>(nruns);
  n_supers_ = 0;
  for (int c = 0; c < dense_from_;) {
    int w = 1;
    while (c + w < dense_from_) {  // does column c + w - 1 nest onto column c + w?
      const int a = c + w - 1, b = c + w;
      const int na = col_start_[a + 1] - col_start_[a], nb = col_start_[b + 1] - col_start_[b];
      if (na != nb + 1 || col_rows_[col_start_[a]] != b ||
          !std::equal(col_rows_.begin() + col_start_[a] + 1, col_rows_.begin() + col_start_[a + 1],
                      col_rows_.begin() + col_start_[b]))
        break;
      ++w;
    }
    supers_[n_supers_++] = Supernode{static_cast<std::uint8_t>(c), static_cast<std::uint8_t>(w)};
    c += w;
  }
  // A's entries outside the factor's pattern (covers(a)), in runs.
  n_zeros_ = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j <= i; ++j) {
      if (filled_[i] & bit(j)) continue;
      const std::uint32_t src = rows_[i] * stride + rows_[j];
      if (n_zeros_ > 0 && zeros_[n_zeros_ - 1].src + zeros_[n_zeros_ - 1].count == src)
        ++zeros_[n_zeros_ - 1].count;
      else
        zeros_[n_zeros_++] = Zeros{src, 1};
    }
  }
  // Copies row by row (runs along a row of both matrices), the sparse part then the tail.
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < std::min(r, dense_from_); ++c)
      if (below_of[c] >> r & 1) copy(r, c);
    if (r < dense_from_) copy(r, r);
    for (int c = dense_from_; c <= r; ++c) copy(r, c);
  }

  // ---- For SparseLdlt::factor (session 10): the copies as runs contiguous in the working
  // matrix only, each entry with its own source (fewer, longer runs than copies_, whose runs
  // must be contiguous in A as well).
  n_fills_ = 0;
  int nsrc = 0;
  for (int g = 0; g < n_copies_; ++g) {
    const Copy& c = copies_[g];
    Fill* last = n_fills_ > 0 ? &fills_[n_fills_ - 1] : nullptr;
    if (last && last->dst + last->count == c.dst) {
      last->count = static_cast<std::uint16_t>(last->count + c.count);
    } else {
      fills_[n_fills_++] = Fill{static_cast<std::uint16_t>(nsrc), c.dst, c.count};
    }
    for (int e = 0; e < c.count; ++e) fill_src_[nsrc++] = c.src + e;
  }
}

}  // namespace ernest::dynamics
