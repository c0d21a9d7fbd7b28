// The constraint solver's memory between steps (lcp_workspace.hpp's LcpWorkspace): the remembered
// LDLᵀ plans (round robin over kPlans row sets, grown when a new pattern falls outside), the
// remembered active-set guesses, and both carried through a Snapshot (save / load).
#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "ernest/solver/lcp_workspace.hpp"

namespace ernest::solver {

LdltPlan* LcpWorkspace::find(const unsigned* rows, int n, int stride) {
  for (int q = 0; q < kPlans; ++q)  // (a constant count: unrolled)
    if (q < n_plans && plans[q].same_rows(rows, n, stride)) return &plans[q];
  return nullptr;
}

LdltPlan* LcpWorkspace::find(LdltPlan::Mask rows, int n, int stride) {
  for (int q = 0; q < kPlans; ++q)  // (a plan's row set is 0 only if it has a row past 127)
    if (q < n_plans && plans[q].row_set() == rows && plans[q].size() == n &&
        plans[q].stride() == stride)
      return &plans[q];
  return nullptr;
}

const LdltPlan& LcpWorkspace::adopt(LdltPlan* remembered, const LdltPlan::Mask* pattern,
                                    const unsigned* rows, int n, int stride) {
  if (remembered) {  // grow its pattern
    std::array<LdltPlan::Mask, LdltPlan::kMaxRows> u;
    for (int i = 0; i < n; ++i) u[i] = remembered->pattern()[i] | pattern[i];
    remembered->analyse(u.data(), rows, n, stride);
    ++plans_grown;
    return *remembered;
  }
  LdltPlan& p = plans[next_plan];
  n_plans = std::max(n_plans, next_plan + 1);
  next_plan = (next_plan + 1) % kPlans;
  p.analyse(pattern, rows, n, stride);
  ++plans_made;
  return p;
}

LcpWorkspace::Guess* LcpWorkspace::guess_for(unsigned n, LdltPlan::Mask bounded) {
  for (Guess& g : guesses)
    if (g.n == n && g.bounded == bounded) return &g;
  return nullptr;
}

void LcpWorkspace::remember(Guess* known, unsigned n, LdltPlan::Mask bounded,
                            LdltPlan::Mask active, LdltPlan::Mask at_lo) {
  if (!known) {
    known = &guesses[next_guess];
    next_guess = (next_guess + 1) % kGuesses;
  }
  *known = Guess{n, bounded, active, at_lo};
}

void LcpWorkspace::clear() {
  n_plans = 0;
  next_plan = 0;
  guesses = {};
  next_guess = 0;
  ++factors;  // (ldlt's factor may refer to a plan that goes)
  factored_n = 0;
}

// Layout: next_plan, then per slot n (0: not remembered; only after the remembered ones),
// stride, rows[n], pattern[n]; then
// next_guess and per guess n, bounded, active, at_lo; each row set (mask) as two words, low first.
void LcpWorkspace::save(std::vector<std::uint64_t>& out) const {
  out.clear();
  const auto put = [&](LdltPlan::Mask m) {
    out.push_back(static_cast<std::uint64_t>(m));
    out.push_back(static_cast<std::uint64_t>(m >> 64));
  };
  out.push_back(static_cast<std::uint64_t>(next_plan));
  for (int q = 0; q < kPlans; ++q) {
    const LdltPlan& p = plans[q];
    out.push_back(q < n_plans ? static_cast<std::uint64_t>(p.size()) : 0u);
    if (q >= n_plans) continue;
    out.push_back(static_cast<std::uint64_t>(p.stride()));
    for (int i = 0; i < p.size(); ++i) out.push_back(p.rows()[i]);
    for (int i = 0; i < p.size(); ++i) put(p.pattern()[i]);
  }
  out.push_back(static_cast<std::uint64_t>(next_guess));
  for (const Guess& g : guesses) {
    out.push_back(g.n);
    put(g.bounded);
    put(g.active);
    put(g.at_lo);
  }
}

void LcpWorkspace::load(const std::vector<std::uint64_t>& in) {
  const auto bad = [] {
    throw std::invalid_argument("Snapshot: corrupt constraint-solver data (not from snapshot())");
  };
  clear();
  if (in.empty()) return;  // a snapshot from before any step
  std::size_t k = 0;
  const auto next = [&] {
    if (k >= in.size()) bad();
    return in[k++];
  };
  const auto mask = [&] {
    const LdltPlan::Mask lo = next();
    return lo | LdltPlan::Mask{next()} << 64;
  };
  const std::uint64_t np = next();
  if (np >= kPlans) bad();
  int remembered = 0;
  for (int q = 0; q < kPlans; ++q) {
    LdltPlan& p = plans[q];
    const std::uint64_t n = next();
    if (n == 0) continue;
    if (n > LdltPlan::kMaxRows || q != remembered++) bad();  // the remembered slots come first
    const std::uint64_t stride = next();
    std::array<unsigned, LdltPlan::kMaxRows> rows;
    std::array<LdltPlan::Mask, LdltPlan::kMaxRows> pattern;
    for (std::uint64_t i = 0; i < n; ++i) {
      rows[i] = static_cast<unsigned>(next());
      if (rows[i] >= stride || (i > 0 && rows[i] <= rows[i - 1])) bad();
    }
    for (std::uint64_t i = 0; i < n; ++i) {
      pattern[i] = mask();
      if ((pattern[i] >> i) != 1) bad();  // lower triangle with its diagonal
    }
    if (stride > 4 * LdltPlan::kMaxRows) bad();
    p.analyse(pattern.data(), rows.data(), static_cast<int>(n), static_cast<int>(stride));
  }
  const std::uint64_t ng = next();
  if (ng >= kGuesses) bad();
  for (Guess& g : guesses) {
    const std::uint64_t n = next();
    const LdltPlan::Mask bounded = mask(), active = mask(), at_lo = mask();
    if (n > LdltPlan::kMaxRows || (active & ~bounded) != 0 || (at_lo & ~bounded) != 0 ||
        (at_lo & active) != 0)
      bad();
    g = Guess{static_cast<unsigned>(n), bounded, active, at_lo};
  }
  if (k != in.size()) bad();
  // Round robin fills the slots in order: the next one is the first empty one until all are used.
  if (remembered < kPlans && np != static_cast<std::uint64_t>(remembered)) bad();
  n_plans = remembered;
  next_plan = static_cast<int>(np);
  next_guess = static_cast<int>(ng);
}

}  // namespace ernest::solver
