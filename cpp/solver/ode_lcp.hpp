// The constraint solve of dWorldStep through a sparse LDLᵀ (the solver hook).
//
// dWorldStep hands ODE's Dantzig LCP solver the dense matrix A = J M⁻¹ Jᵀ of all rows. With the
// guessed active set (rover_step.cpp) almost every row is unbounded, and the rest are contact
// normals bounded below by zero, whose state (pushing or not) repeats from step to step, so the LCP
// is one linear system plus a check per bounded row; ODE still factorises A densely, permuting rows
// one at a time. ode_lcp.cpp defines ODE's (exported, called through the PLT) dxSolveLCP, so that
// the dynamic linker binds ODE's call to it: while a LcpScope is alive on the thread, such problems
// are solved with SparseLdlt (the bounded rows guessed as they ended last time) and checked exactly
// as Dantzig's method would end; anything else (friction with findex unless
// LcpWorkspace::coulomb_friction, a bounded row without a zero bound, guesses that keep failing,
// more than 128 rows, no scope) goes to ODE's own solver, found with dlsym. ODE bounds a friction
// row by mu times the normal force found before the friction rows; within a scope that asks for it
// (exact_friction) its answer is then corrected to Coulomb's law with the final normal force
// (solve_coulomb, coulomb_lcp.hpp). The solve itself: solve_sparse (sparse_lcp.hpp); its state:
// LcpWorkspace (lcp_workspace.hpp).
#pragma once

#include <string>

#include "ernest/solver/lcp_workspace.hpp"
#include "ernest/solver/sparse_lcp.hpp"

namespace ernest::solver {

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
