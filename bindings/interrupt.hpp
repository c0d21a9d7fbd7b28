// Ctrl-C inside long C++ calls. A binding that releases the GIL for a long call opens
// an interrupt scope after releasing it:
//   py::call_guard<py::gil_scoped_release, ernest::bindings::interruptible>()
// or, inside a lambda, `py::gil_scoped_release release; interruptible scope;`. The C++ loops poll
// (cpp/common/interrupt.hpp); every 50 ms the calling thread takes the GIL for a moment and runs
// Python's signal handlers (PyErr_CheckSignals). If one raised (KeyboardInterrupt for Ctrl-C), the
// call stops at its next consistent point and that very exception reaches the caller (the
// translator registered in module.cpp). Only the main thread runs signal handlers (Python's rule).
#pragma once

#include <pybind11/pybind11.h>

#include <memory>

#include "ernest/common/interrupt.hpp"

namespace ernest::bindings {

/// The exception a signal handler raised during the current call on this thread, if any.
inline std::unique_ptr<pybind11::error_already_set>& pending_signal_error() {
  thread_local std::unique_ptr<pybind11::error_already_set> error;
  return error;
}

/// InterruptScope's check: run the pending signal handlers under the GIL.
inline bool python_signal_raised() {
  pybind11::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() == 0) return false;
  pending_signal_error() = std::make_unique<pybind11::error_already_set>();  // fetches it
  return true;
}

/// Call guard: the wrapped call can be interrupted (use after gil_scoped_release).
struct interruptible {
  InterruptScope scope{&python_signal_raised};
};

/// Registered once (module.cpp): ernest::Interrupted -> the handler's exception, else
/// KeyboardInterrupt.
inline void register_interrupt_translator() {
  pybind11::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Interrupted& e) {
      std::unique_ptr<pybind11::error_already_set> pending = std::move(pending_signal_error());
      if (pending) pending->restore();
      else PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
    }
  });
}

}  // namespace ernest::bindings
