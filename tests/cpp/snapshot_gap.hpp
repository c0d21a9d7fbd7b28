// The largest difference between two rover snapshots' bodies, shared by the solver tests.
#pragma once

#include <algorithm>
#include <cmath>

#include "ernest/dynamics/rover_sim.hpp"

namespace ernest::testing {

/// Max over the six bodies of |Δ position|, |Δ velocity| and |Δ angular velocity| × 0.17 m (the
/// tyre radius): [m] or [m/s] at the tyre.
inline double body_gap(const dynamics::Snapshot& a, const dynamics::Snapshot& b) {
  double gap = 0.0;
  for (int k = 0; k < 6; ++k) {
    for (int d = 0; d < 3; ++d) {
      gap = std::max(gap, std::abs(a.bodies[k].pos[d] - b.bodies[k].pos[d]));
      gap = std::max(gap, std::abs(a.bodies[k].lin[d] - b.bodies[k].lin[d]));
      gap = std::max(gap, std::abs(a.bodies[k].ang[d] - b.bodies[k].ang[d]) * 0.17);
    }
  }
  return gap;
}

}  // namespace ernest::testing
