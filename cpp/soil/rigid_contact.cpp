#include "ernest/soil/rigid_contact.hpp"

#include "ernest/common/validation.hpp"

namespace ernest::soil {

void RigidContactParameters::validate() const {
  const char* o = "RigidContactParameters";
  require_positive(o, "stiffness", stiffness);
  require_in_range(o, "damping", damping, 0.0, kInf);
  require_in_range(o, "friction_min", friction_min, 0.0, 10.0);
  require_in_range(o, "friction_max", friction_max, friction_min, 10.0);
}

// A spring k and damper c integrated by ODE's semi-implicit step h behave as ERP = hk / (hk + c),
// CFM = 1 / (hk + c) (ODE manual, "Joint error and the ERP" / "Soft constraint and CFM").
double RigidContactParameters::erp(double dt) const {
  require_positive("RigidContactParameters.erp", "dt", dt);
  return dt * stiffness / (dt * stiffness + damping);
}

double RigidContactParameters::cfm(double dt) const {
  require_positive("RigidContactParameters.cfm", "dt", dt);
  return 1.0 / (dt * stiffness + damping);
}

double RigidContactParameters::sample_friction(std::mt19937_64& rng) const {
  std::uniform_real_distribution<double> u(friction_min, friction_max);
  return friction_min == friction_max ? friction_min : u(rng);
}

}  // namespace ernest::soil
