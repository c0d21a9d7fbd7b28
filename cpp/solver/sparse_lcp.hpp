// The LCP of a constraint step solved as one sparse linear system (solve_sparse): the bounded
// rows' active set guessed as it ended last time, solved with SparseLdlt (sparse_ldlt.hpp),
// friction rows at a bound as a low-rank correction of the same factor, and the answer checked
// exactly as Dantzig's method would end; false hands the problem back to ODE's solver.
#pragma once

#include <cstdint>

#include "ernest/solver/lcp_workspace.hpp"

namespace ernest::solver {

/// ODE's LCP (A x = b + w, lo <= x <= hi with complementarity; A's lower triangle, row stride
/// dPAD(n); b and x interleaved in pairsbx, lo and hi in pairslh; findex: friction rows; the first
/// nub rows unbounded) solved with the sparse LDLᵀ and the remembered guesses of `ws`, checked as
/// Dantzig's method ends (sparse_lcp.cpp). Returns false, the outputs untouched, if it cannot (then
/// ODE's Dantzig solver must). Called by the solver hook (ode_lcp.cpp), and directly by our own
/// island step (island_step.hpp). Does not count the solve (LcpWorkspace::sparse): the caller does.
/// kept_factor: ws.factors after an earlier call with this very A (bit for bit; IslandStep::
/// resolve); while no factorisation happened since, a guess that solves the rows of that call's
/// last factor uses it as it is (the same bits as factorising A again). 0: none.
bool solve_sparse(LcpWorkspace& ws, unsigned n, const double* A, double* pairsbx, double* outer_w,
                  unsigned nub, const double* pairslh, const int* findex,
                  std::uint64_t kept_factor = 0);

}  // namespace ernest::solver
