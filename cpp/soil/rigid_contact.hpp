// Rigid wheel–obstacle contact of seed 004 §3.4: linear spring–damper with Coulomb friction.
#pragma once

#include <random>

namespace ernest::soil {

struct RigidContactParameters {
  double stiffness = 20e3;     ///< [N/m], wheel compression experiment (Fig. 9)
  double damping = 20.0;       ///< [N s/m], from drop-test rebound height
  double friction_min = 0.5;   ///< Coulomb friction is sampled uniformly in [min, max]
  double friction_max = 0.9;

  void validate() const;
  /// ODE's error-reduction parameter reproducing the spring–damper for step dt.
  double erp(double dt) const;
  /// ODE's constraint-force mixing reproducing the spring–damper for step dt.
  double cfm(double dt) const;
  /// Uniform draw of the friction coefficient in [friction_min, friction_max].
  double sample_friction(std::mt19937_64& rng) const;
};

}  // namespace ernest::soil
