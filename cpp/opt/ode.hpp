// Adaptive Boost.Numeric.Odeint integration with progress checks, shared by the kinematics
// (eqs 20–23) and the sensitivity equations of the transition optimiser.
#pragma once

#include <boost/numeric/odeint.hpp>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "ernest/opt/asterix_model.hpp"

namespace ernest::opt::detail {

/// Integrates dx/dt = system(x, t) from t0 to t1 (t1 >= t0) with a controlled Dormand–Prince 5(4)
/// stepper. odeint's own errors (step-size adjustment failures) and ours (too many steps, step
/// underflow, non-finite state) become KinematicsError naming `what` and the time reached.
/// `pieces` splits [t0, t1] into equal sub-intervals that no step crosses (the spline trajectories
/// have knots there, where the right-hand side is only C0 in its derivative).
template <class State, class System>
void integrate_checked(System&& system, State& x, double t0, double t1,
                       const IntegrationOptions& options, const char* what, int pieces = 1) {
  namespace ode = boost::numeric::odeint;
  if (!(t1 > t0)) return;
  auto stepper = ode::make_controlled<ode::runge_kutta_dopri5<State>>(options.abs_tol,
                                                                      options.rel_tol);
  double t = t0;
  pieces = std::max(pieces, 1);
  const double piece = (t1 - t0) / pieces;
  double dt = piece;
  ode::max_step_checker checker(options.max_steps);
  try {
    for (int k = 0; k < pieces; ++k) {
    const double end = k + 1 == pieces ? t1 : t0 + piece * (k + 1);
    dt = std::min(dt, end - t);
    while (t < end) {
      checker();  // throws ode::no_progress_error past max_steps
      if (t + dt > end) dt = end - t;
      const double t_before = t;
      const ode::controlled_step_result r = stepper.try_step(system, x, t, dt);
      if (r == ode::success) {
        if (end - t <= 1e-12 * piece) t = end;  // land exactly on the knot
        for (const double v : x) {
          if (!std::isfinite(v)) {
            std::ostringstream os;
            os << what << ": state became non-finite at t = " << t;
            throw KinematicsError(os.str());
          }
        }
      }
      if (dt < 1e-14 * std::max(1.0, std::abs(t1 - t0)) && t == t_before) {
        std::ostringstream os;
        os << what << ": step size underflow (dt = " << dt << ") at t = " << t;
        throw KinematicsError(os.str());
      }
    }
    }
  } catch (const ode::odeint_error& e) {  // no_progress_error, step_adjustment_error
    std::ostringstream os;
    os << what << ": odeint made no progress at t = " << t << " of [" << t0 << ", " << t1
       << "]: " << e.what();
    throw KinematicsError(os.str());
  }
}

}  // namespace ernest::opt::detail
