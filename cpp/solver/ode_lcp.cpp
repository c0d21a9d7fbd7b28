// ODE's LCP entry point, bound to the sparse solver (see ode_lcp.hpp for why and when).
#include "ernest/solver/ode_lcp.hpp"

#include <dlfcn.h>
#include <ode/ode.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "ernest/solver/coulomb_lcp.hpp"

struct dxWorldProcessMemArena;  // ODE's, opaque here

// ODE 0.16 (src/lcp.cpp): solve A x = b + w with lo <= x <= hi and complementarity, A the n x n
// lower triangle with row stride dPAD(n); b and x interleaved in pairsbx (b, x per row), lo and
// hi in pairslh; findex[i] >= 0 makes row i's bounds friction bounds of row findex[i]; the first
// nub rows are unbounded. The name must mangle exactly as ODE's (the linker matches it).
__attribute__((visibility("default"))) void dxSolveLCP(dxWorldProcessMemArena* memarena,
                                                       unsigned n, dReal* A, dReal* pairsbx,
                                                       dReal* outer_w, unsigned nub,
                                                       dReal* pairslh, int* findex);

namespace ernest::solver {

namespace {

static_assert(sizeof(dReal) == sizeof(double), "ODE must be built in double precision");
using OdeSolve = void (*)(dxWorldProcessMemArena*, unsigned, dReal*, dReal*, dReal*, unsigned,
                          dReal*, int*);
constexpr const char* kSymbol = "_Z10dxSolveLCPP22dxWorldProcessMemArenajPdS1_S1_jS1_Pi";

thread_local LcpWorkspace* current = nullptr;
thread_local bool reached = false;  // our dxSolveLCP ran on this thread (sparse_lcp_active)

// ODE's own solver: the next definition after ours, else the one in libode itself.
OdeSolve ode_solver() {
  static const OdeSolve fn = [] {
    auto f = reinterpret_cast<OdeSolve>(dlsym(RTLD_NEXT, kSymbol));
    if (f == nullptr || f == &::dxSolveLCP) {
      void* lib = dlopen("libode.so.8", RTLD_LAZY | RTLD_NOLOAD);
      if (lib) f = reinterpret_cast<OdeSolve>(dlsym(lib, kSymbol));
    }
    return f == &::dxSolveLCP ? nullptr : f;
  }();
  return fn;
}

}  // namespace

LcpScope::LcpScope(LcpWorkspace* ws) { current = ws; }
LcpScope::~LcpScope() { current = nullptr; }

namespace {

thread_local bool probing = false;  // sparse_lcp_active() is stepping its probe world

// One step of a probe world through the hook: a tumbling box held at a point by a ball joint
// (three unbounded rows) above a frictionless contact that separates (a row resting at its
// zero bound). Returns the box's velocities; `sparse` chooses the solver.
std::array<double, 6> probe_step(bool sparse, LcpWorkspace& ws) {
  dWorldID w = dWorldCreate();
  dWorldSetGravity(w, 0.0, 0.0, -9.81);
  dJointGroupID group = dJointGroupCreate(0);
  dBodyID b = dBodyCreate(w);
  dMass m;
  dMassSetBoxTotal(&m, 2.0, 0.3, 0.2, 0.1);
  dBodySetMass(b, &m);
  dBodySetPosition(b, 0.1, 0.0, 0.5);
  dBodySetLinearVel(b, 0.2, -0.1, 0.5);
  dBodySetAngularVel(b, 1.0, 2.0, -0.5);
  dJointID ball = dJointCreateBall(w, group);
  dJointAttach(ball, b, nullptr);
  dJointSetBallAnchor(ball, 0.0, 0.05, 0.55);
  dContact c{};
  c.geom.pos[2] = 0.4;
  c.geom.normal[2] = 1.0;
  dJointAttach(dJointCreateContact(w, group, &c), b, nullptr);
  ws.enabled = sparse;
  {
    const LcpScope scope(&ws);
    dWorldStep(w, 0.01);
  }
  std::array<double, 6> v;
  for (int k = 0; k < 3; ++k) {
    v[k] = dBodyGetLinearVel(b)[k];
    v[3 + k] = dBodyGetAngularVel(b)[k];
  }
  dJointGroupDestroy(group);
  dWorldDestroy(w);
  return v;
}

}  // namespace

namespace {

// The probe's verdict: "" when the sparse path is active, else why not (for the warning).
const std::string& probe_verdict() {
  static const std::string verdict = [] {
    // ODE's calls reach the hook, ODE's own solver is there to fall back on, and on a probe
    // step the sparse path answers as ODE's solver does (a check that ODE's data layout is the
    // one solve_sparse() reads). Otherwise every solve goes to ODE.
    probing = true;
    reached = false;
    auto ws = std::make_unique<LcpWorkspace>();
    const std::array<double, 6> ode = probe_step(false, *ws);
    const bool hooked = reached;
    const std::array<double, 6> ours = probe_step(true, *ws);
    probing = false;
    std::string why;
    if (!hooked) {
      why = "ODE's constraint solves do not reach ernest's dxSolveLCP (this libode binds its "
            "call internally, or names it otherwise than " + std::string(kSymbol) + ")";
    } else {
      if (ode_solver() == nullptr)  // ODE would get no solver at all: refuse to run
        throw std::runtime_error("ODE's dxSolveLCP (" + std::string(kSymbol) + ") not found");
      bool same = ws->sparse == 1 && ws->dense == 1;
      for (int k = 0; k < 6; ++k)
        same = same && std::abs(ours[k] - ode[k]) <= 1e-12 * (1.0 + std::abs(ode[k]));
      if (!same)
        why = "the sparse solver's answer to a probe step differs from ODE's (this libode's "
              "data layout is not ODE 0.16's)";
    }
    // Once per process: a warning, not an error (the simulation still runs, on ODE's solver).
    if (!why.empty())
      std::fprintf(stderr,
                   "ernest: warning: the fast constraint solver is off: %s; every step uses "
                   "ODE's Dantzig solver: slower, and friction bounded by ODE's approximation "
                   "(not corrected to Coulomb's law with the final normal force). See "
                   "ARCHITECTURE.md, \"The solver hook\".\n",
                   why.c_str());
    return why;
  }();
  return verdict;
}

}  // namespace

bool sparse_lcp_active() { return probe_verdict().empty(); }

const std::string& sparse_lcp_inactive_reason() { return probe_verdict(); }

}  // namespace ernest::solver

void dxSolveLCP(dxWorldProcessMemArena* memarena, unsigned n, dReal* A, dReal* pairsbx,
                dReal* outer_w, unsigned nub, dReal* pairslh, int* findex) {
  using namespace ernest::solver;
  reached = true;
  LcpWorkspace* ws = current;
  if (ws && ws->enabled && (probing || sparse_lcp_active()) &&
      solve_sparse(*ws, n, A, pairsbx, outer_w, nub, pairslh, findex)) {
    ++ws->sparse;
    return;
  }
  if (ws) ++ws->dense;
  const OdeSolve ode = ode_solver();
  if (!ode) {  // unreachable: sparse_lcp_active() refuses to run without it
    for (unsigned i = 0; i < n; ++i) pairsbx[2 * i + 1] = 0.0;
    return;
  }
  // Friction rows (within a scope, and not too many rows): keep the problem for solve_coulomb.
  bool coulomb = false;
  if (ws && ws->exact_friction && findex &&
      n <= static_cast<unsigned>(ernest::solver::LdltPlan::kMaxRows)) {
    for (unsigned i = nub; i < n && !coulomb; ++i) coulomb = findex[i] >= 0;
  }
  if (coulomb) {
    std::copy(A, A + static_cast<std::size_t>(n) * dPAD(n), ws->a_copy.begin());
    std::copy(pairsbx, pairsbx + 2 * n, ws->bx_copy.begin());
    std::copy(pairslh, pairslh + 2 * n, ws->lh_copy.begin());
    std::copy(findex, findex + n, ws->findex_copy.begin());
  }
  ode(memarena, n, A, pairsbx, outer_w, nub, pairslh, findex);
  if (coulomb && !solve_coulomb(*ws, n, nub, pairsbx, outer_w)) ++ws->friction_unresolved;
}
