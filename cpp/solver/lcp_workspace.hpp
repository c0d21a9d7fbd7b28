// The constraint solver's state between steps (LcpWorkspace): the remembered LDLᵀ plans and
// active-set guesses (lcp_workspace.cpp), the switches a simulator sets (enabled, exact_friction,
// coulomb_friction) and the counters of what the solves did (sparse, dense, plans_made, ...).
// One per simulation; solve_sparse (sparse_lcp.hpp), solve_coulomb (coulomb_lcp.hpp) and the
// solver hook (ode_lcp.hpp) work in it.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "ernest/solver/sparse_ldlt.hpp"

namespace ernest::solver {

/// Working data of one simulation's constraint solves, and what they did.
///
/// Plans are remembered per set of solved rows. The numeric pattern of A flickers as the rover
/// moves through symmetric poses (an entry between two rows on one body is exactly zero in some
/// configurations), so a plan is analysed from the union of the patterns its rows have shown and
/// kept while every new pattern lies within its factor. On rocks most row sets are new (a
/// contact's rows renumber the rows after them: 85 of the 123 plans made in 850 steps of
/// benchmarks/profile_rocks on 20 rocks), so more plans save few analyses, and evicting the least
/// recently used keeps grown plans longer, which factorise more slowly than the analyses they
/// save: the oldest plan makes room (benchmarks/RESULTS.md, "Measured and not kept"). Which
/// bounded rows were solved inside their bounds is remembered per set of bounded rows and is the
/// next guess. Both depend on the history: save() and load() carry them through Snapshot, and
/// clear() starts a run afresh (reset), so that repeats stay bit-exact.
struct LcpWorkspace {
  bool enabled = true;  // false: count the solves, hand all of them to ODE
  static constexpr int kPlans = 4;  // sets of rows remembered (a wheel leaving the ground and back)
  std::array<LdltPlan, kPlans> plans{};
  int n_plans = 0;    // plans[0, n_plans) are remembered (clear() need not wipe 650 kB of plans)
  int next_plan = 0;  // the slot of the next new plan (round robin)
  /// Plans analysed (LdltPlan::analyse) for row sets not remembered, and remembered plans
  /// analysed again grown by a pattern outside their factor (counted from construction).
  std::uint64_t plans_made = 0, plans_grown = 0;
  /// Bounded rows (bit i: row i) solved inside their bounds when these rows were bounded.
  /// Friction rows (findex) are bounded rows too: active = inside, else at +-mu x_k (at_lo: -).
  struct Guess {
    unsigned n = 0;
    LdltPlan::Mask bounded = 0, active = 0, at_lo = 0;
  };
  static constexpr int kGuesses = 4;
  std::array<Guess, kGuesses> guesses{};
  int next_guess = 0;
  SparseLdlt ldlt;
  std::uint64_t sparse = 0;    // solves done here
  std::uint64_t dense = 0;     // solves handed to ODE's Dantzig solver
  /// Correct ODE's friction (findex) bounds to mu times the final normal force (solve_coulomb in
  /// coulomb_lcp.cpp). Set for rigid ground, whose sliding tyres need it; off on soil, where only
  /// rock contacts have friction rows and the correction (a dense solve of every rock-contact step)
  /// would double the rock field's step time.
  bool exact_friction = false;
  /// Solve friction (findex) rows in the sparse path too, each guessed inside its bound or at +-mu
  /// times its contact's final normal force (Coulomb's law, as solve_coulomb; solve_sparse in
  /// sparse_lcp.cpp). Off: such problems go to ODE's Dantzig solver (and its approximate bound).
  /// Set on soil, where only the rocks' contacts have friction rows.
  bool coulomb_friction = false;
  /// A_SS⁻¹ A_Si of the friction rows at a bound (solve_sparse), one column per row.
  std::array<double, LdltPlan::kMaxRows * LdltPlan::kMaxRows> clamped_cols{};
  /// What clamped_cols were computed for: the factor (serial of `factors`: it fixes the problem
  /// and its solved rows), the friction rows at a bound and their signed mu (0: nothing kept).
  struct ClampedColumns {
    std::uint64_t factor = 0;
    LdltPlan::Mask mask = 0;
    std::array<double, LdltPlan::kMaxRows> scale{};
  };
  ClampedColumns clamped;
  /// Dense solves with friction (findex) rows whose bounds could not be made mu times the final
  /// normal force (ODE's approximate answer stands; see solve_coulomb in coulomb_lcp.cpp).
  std::uint64_t friction_unresolved = 0;
  /// The problem as ODE received it (its solver overwrites A), for solve_coulomb.
  std::array<double, LdltPlan::kMaxRows * LdltPlan::kMaxRows> a_copy{};
  std::array<double, 2 * LdltPlan::kMaxRows> bx_copy{}, lh_copy{};
  std::array<int, LdltPlan::kMaxRows> findex_copy{};
  /// Factorisations made in ldlt (a serial: 0 none yet; clear() counts one, its plans go), and
  /// the last one's rows and problem size: what solve_sparse's kept_factor refers to.
  std::uint64_t factors = 0;
  LdltPlan::Mask factored = 0;
  unsigned factored_n = 0;

  /// The remembered plan for these rows, or nullptr.
  LdltPlan* find(const unsigned* rows, int n, int stride);
  /// The same for rows given as a set (bit r: row r; n of them): no walk over the rows.
  LdltPlan* find(LdltPlan::Mask rows, int n, int stride);
  /// A plan covering this pattern: `remembered` (find()'s answer) grown by it, or a new one.
  const LdltPlan& adopt(LdltPlan* remembered, const LdltPlan::Mask* pattern,
                        const unsigned* rows, int n, int stride);
  /// The remembered guess for this set of bounded rows, or nullptr; remember() stores one.
  Guess* guess_for(unsigned n, LdltPlan::Mask bounded);
  void remember(Guess* known, unsigned n, LdltPlan::Mask bounded, LdltPlan::Mask active,
                LdltPlan::Mask at_lo);
  void clear();
  void save(std::vector<std::uint64_t>& out) const;
  /// Inverse of save(); throws std::invalid_argument on data that save() cannot have written.
  void load(const std::vector<std::uint64_t>& in);
};

}  // namespace ernest::solver
