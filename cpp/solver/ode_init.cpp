// ODE's process-wide set-up: initialisation and chained handlers (see ode_init.hpp).
#include "ernest/solver/ode_init.hpp"

#include <ode/ode.h>

#include <cstdarg>
#include <cstdio>
#include <mutex>

#include "ernest/solver/ode_lcp.hpp"

namespace ernest::solver {

thread_local std::uint64_t ode_lcp_messages = 0;

namespace {

thread_local int own_calls = 0;  // OdeCallScope depth on this thread

// The handlers installed before ours (nullptr: ODE's default, which prints and, for errors and
// debug reports, then exits or aborts). Written once, before ours are installed.
dMessageFunction* previous_message = nullptr;
dMessageFunction* previous_error = nullptr;
dMessageFunction* previous_debug = nullptr;

// What ODE does without a handler (ode/src/error.cpp, printMessage).
void print_like_ode(const char* what, int num, const char* msg, va_list ap) {
  std::fflush(stdout);
  if (num != 0) std::fprintf(stderr, "\n%s %d: ", what, num);
  else std::fprintf(stderr, "\n%s: ", what);
  std::vfprintf(stderr, msg, ap);
  std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

// ODE reports LCP trouble through its message handler. Inside our steps the step counts it
// (SolverStats::lcp_errors; the divergence check is our error channel); anything else is the
// previous handler's.
void on_message(int num, const char* msg, va_list ap) {
  if (own_calls > 0 && num == d_ERR_LCP) {
    ++ode_lcp_messages;
    return;
  }
  if (previous_message) previous_message(num, msg, ap);
  else print_like_ode("ODE Message", num, msg, ap);
}

// ODE's error and debug handlers must not return (ODE exits or aborts if they do). In our steps,
// or when nobody installed a handler before us, throw instead, through ODE's C++ frames (built
// with unwind tables), to RoverSim::Impl::run_ode(); otherwise the previous handler decides.
[[noreturn]] void throw_ode_error(int num, const char* msg, va_list ap) {
  char text[512];
  std::vsnprintf(text, sizeof text, msg, ap);
  throw OdeInternalError("ODE error " + std::to_string(num) + ": " + text);
}

void on_error(int num, const char* msg, va_list ap) {
  if (own_calls == 0 && previous_error) return previous_error(num, msg, ap);
  throw_ode_error(num, msg, ap);
}

void on_debug(int num, const char* msg, va_list ap) {
  if (own_calls == 0 && previous_debug) return previous_debug(num, msg, ap);
  throw_ode_error(num, msg, ap);
}

}  // namespace

void init_ode_once() {
  static std::once_flag flag;
  std::call_once(flag, [] {
    dInitODE2(0);
    previous_message = dGetMessageHandler();
    previous_error = dGetErrorHandler();
    previous_debug = dGetDebugHandler();
    dSetMessageHandler(on_message);
    dSetErrorHandler(on_error);
    dSetDebugHandler(on_debug);
  });
  // Every thread that steps a world needs ODE's per-thread data (collision caches).
  thread_local bool allocated = false;
  if (!allocated) {
    dAllocateODEDataForThread(dAllocateMaskAll);
    allocated = true;
  }
}

std::uint64_t ode_lcp_message_count() { return ode_lcp_messages; }

OdeCallScope::OdeCallScope() { ++own_calls; }
OdeCallScope::~OdeCallScope() { --own_calls; }

bool fast_lcp_active() {
  init_ode_once();
  return sparse_lcp_active();
}

std::string fast_lcp_inactive_reason() {
  init_ode_once();
  return sparse_lcp_inactive_reason();
}

}  // namespace ernest::solver
