// The constraint solve of dWorldStep through a sparse LDLᵀ (the solver hook).
//
// dWorldStep hands ODE's Dantzig LCP solver the dense matrix A = J M⁻¹ Jᵀ of all rows. With the
// guessed active set (rover_step.cpp) almost every row is unbounded, and the rest are contact
// normals bounded below by zero, whose state (pushing or not) repeats from step to step, so the
// LCP is one linear system plus a check per bounded row; ODE still factorises A densely,
// permuting rows one at a time. ode_lcp.cpp defines ODE's (exported, called through the PLT)
// dxSolveLCP, so that the dynamic linker binds ODE's call to it: while a LcpScope is alive on
// the thread, such problems are solved with SparseLdlt (the bounded rows guessed as they ended
// last time) and checked exactly as Dantzig's method would end; anything else (friction with
// findex unless LcpWorkspace::coulomb_friction, a bounded row without a zero bound, guesses that keep failing, more than 128 rows, no
// scope) goes to ODE's own solver, found with dlsym. ODE bounds a friction row by mu times the
// normal force found before the friction rows; within a scope that asks for it (exact_friction)
// its answer is then corrected to Coulomb's law with the final normal force (solve_coulomb).
#pragma once

#include <array>
#include <cstdint>
#include <string>
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
  /// ode_lcp.cpp). Set for rigid ground, whose sliding tyres need it; off on soil, where only rock
  /// contacts have friction rows and the correction (a dense solve of every rock-contact step)
  /// would double the rock field's step time.
  bool exact_friction = false;
  /// Solve friction (findex) rows in the sparse path too, each guessed inside its bound or at
  /// +-mu times its contact's final normal force (Coulomb's law, as solve_coulomb; solve_sparse
  /// in ode_lcp.cpp). Off: such problems go to ODE's Dantzig solver (and its approximate bound).
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
  /// normal force (ODE's approximate answer stands; see solve_coulomb in ode_lcp.cpp).
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

/// ODE's LCP (A x = b + w, lo <= x <= hi with complementarity; A's lower triangle, row stride
/// dPAD(n); b and x interleaved in pairsbx, lo and hi in pairslh; findex: friction rows; the first
/// nub rows unbounded) solved with the sparse LDLᵀ and the remembered guesses of `ws`, checked as
/// Dantzig's method ends (ode_lcp.cpp). Returns false, the outputs untouched, if it cannot (then
/// ODE's Dantzig solver must). Called by the hook below, and directly by our own island step
/// (island_step.hpp). Does not count the solve (LcpWorkspace::sparse): the caller does.
/// kept_factor: ws.factors after an earlier call with this very A (bit for bit; IslandStep::
/// resolve); while no factorisation happened since, a guess that solves the rows of that call's
/// last factor uses it as it is (the same bits as factorising A again). 0: none.
bool solve_sparse(LcpWorkspace& ws, unsigned n, const double* A, double* pairsbx, double* outer_w,
                  unsigned nub, const double* pairslh, const int* findex,
                  std::uint64_t kept_factor = 0);

/// While alive, dWorldStep calls on this thread solve through `ws` (not nested).
class LcpScope {
 public:
  explicit LcpScope(LcpWorkspace* ws);
  ~LcpScope();
  LcpScope(const LcpScope&) = delete;
  LcpScope& operator=(const LcpScope&) = delete;
};

/// Whether ODE's calls reach ode_lcp.cpp's solver in this process (the symbol interposition
/// worked) and it answers a probe step as ODE's own solver does; if not, every solve goes to
/// ODE, and the probe prints one warning on stderr. Steps a tiny world twice, once, on first use
/// (ODE must be initialised: init_ode_once); throws std::runtime_error if ODE's calls reach the
/// hook but ODE's own solver cannot be found. Public face: fast_lcp_active() (ode_init.hpp).
bool sparse_lcp_active();
/// Why sparse_lcp_active() is false ("" when it is true).
const std::string& sparse_lcp_inactive_reason();

}  // namespace ernest::solver
