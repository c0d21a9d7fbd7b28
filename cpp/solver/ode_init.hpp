// ODE's process-wide set-up for ernest: initialisation, ODE's message/error/debug handlers (ours
// chained to whoever installed theirs first), and whether the fast constraint solver is active.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace ernest::solver {

/// Whether ODE's constraint solves reach ernest's sparse solver (cpp/solver/ode_lcp.cpp) in
/// this process. The hook works by symbol binding (ARCHITECTURE.md, "The solver hook"): if this
/// libode binds its call internally, names it differently or lays out its data otherwise, every
/// solve goes to ODE's own Dantzig solver instead (slower, and friction bounded by ODE's
/// approximation: no Coulomb correction), and the first call prints one warning on stderr.
/// Initialises ODE; probes once (two steps of a tiny world).
bool fast_lcp_active();

/// Why the fast path is off, for messages; empty while fast_lcp_active().
std::string fast_lcp_inactive_reason();

/// dInitODE2, ernest's ODE handlers (installed once per process, chained to the ones installed
/// before) and this thread's ODE data (once per thread). Call before any other ODE call.
void init_ode_once();

/// Thrown by ernest's error and debug handlers for errors raised inside an OdeCallScope (or when
/// nobody else installed a handler): ODE's default handlers abort the process on an internal
/// error (e.g. "!bSafeNormalize4Fault" on a non-finite state). RoverSim::Impl::run_ode() turns
/// it into SimulationDiverged and retires the simulator; WalkerSim into WalkerSimDiverged.
class OdeInternalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Messages about the LCP that ODE sent on this thread inside an OdeCallScope (counted, not
/// printed: SolverStats::lcp_errors).
extern thread_local std::uint64_t ode_lcp_messages;
/// ode_lcp_messages, read through a call: an executable reading another library's extern
/// thread_local directly trips UBSan's null check after the linker relaxes the TLS access.
std::uint64_t ode_lcp_message_count();

/// Marks this thread as inside one of ernest's own ODE calls (a RoverSim or WalkerSim step):
/// ODE's errors then throw OdeInternalError and its LCP messages are counted. Outside, every
/// message, error and debug report goes to the handler installed before ours (or is printed as
/// ODE's default does), so another ODE user in the process keeps its handlers. Nestable.
class OdeCallScope {
 public:
  OdeCallScope();
  ~OdeCallScope();
  OdeCallScope(const OdeCallScope&) = delete;
  OdeCallScope& operator=(const OdeCallScope&) = delete;
};

}  // namespace ernest::solver
