// Coulomb's law with the final normal force applied to ODE's answer to an LCP with friction
// rows (solve_coulomb): ODE's Dantzig solver bounds a friction row by the normal force of the
// moment it pivots it in; this correction re-solves densely from ODE's active set so that each
// friction row is bounded by mu times the contact's final normal force (seed 004 §3.4).
#pragma once

#include "ernest/solver/lcp_workspace.hpp"

namespace ernest::solver {

/// ODE's answer in pairsbx (x) and outer_w (w) corrected to Coulomb's law with the final normal
/// force, from the problem ODE received as kept in ws.a_copy, bx_copy, lh_copy and findex_copy
/// (n rows, the first nub unbounded). Returns false, leaving ODE's answer, if no guess held
/// (coulomb_lcp.cpp says how the guesses go). Called by the solver hook (ode_lcp.cpp).
bool solve_coulomb(LcpWorkspace& ws, unsigned n, unsigned nub, double* pairsbx,
                   double* outer_w);

}  // namespace ernest::solver
