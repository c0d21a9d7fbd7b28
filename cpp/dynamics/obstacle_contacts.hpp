// Internal to cpp/dynamics: seed 004 §3.4's rigid contact (a linear spring k = 20 kN/m and damper
// c = 20 N s/m along the normal, Coulomb friction) against the obstacles, as ODE contact rows.
// obstacle_contacts.cpp collects the contacts and steps; these are the two pieces of arithmetic it
// is made of, separate so that tests can check them on a single body (test_dynamics_contact.cpp).
#pragma once

#include <ode/ode.h>

#include <Eigen/Core>

#include "ernest/dynamics/cylinder_box.hpp"

namespace ernest::dynamics::detail {

/// One contact per rover-body–obstacle pair from the n points ODE's collider returns (4-6 for a
/// cylinder against a box: the ends of a line contact, the corners of an overlap). The §3.4
/// spring is per wheel–obstacle contact, so the pair gets one row triple: at the depth-weighted
/// mean of the points, along the depth-weighted mean normal (normalised), with the deepest point's
/// depth as the spring's compression (the wheel's radial compression of Fig. 9). Weighting by
/// depth puts a line contact of uniform depth at its middle (no torque from ODE's choice of
/// end points: a wheel on a box top is pushed under its centre, a wheel against a face at its
/// axle height) and lets a point that only grazes count for nothing. Points of zero depth
/// everywhere: their plain mean. geom pointers and sides are the first point's.
dContactGeom merge_contact_points(const dContactGeom* points, int n);

/// The §3.4 spring–damper as the ERP / CFM of a contact row for a step h (ODE's contact row
/// solves J v' = (ERP / h) depth - CFM lambda, lambda >= 0, with depth from the start of the step:
/// ode/src/joints/contact.cpp, c = fps * soft_erp * depth, uncapped since
/// dWorldSetContactMaxCorrectingVel is left at its default, infinity; step.cpp divides CFM by h).
///  - explicit spring, implicit damper (ERP = h k / c, CFM = 1 / c): lambda = k depth - c v_n',
///    symplectic Euler for the contact's oscillator: no numerical damping, the period within
///    (omega h)^2 / 24 of 2 pi / omega, stable while omega h < 2 with omega = sqrt(k / m_eff);
///  - implicit spring and damper (ERP = h k / (h k + c), CFM = 1 / (h k + c)): lambda = k depth(end
///    of step) - c v_n', backward Euler: unconditionally stable but with a numerical damping
///    k h (250 N s/m at 12.5 ms, 12x the tyre's 20).
/// The explicit form is used where omega h <= kMaxExplicitOmegaH for a lower bound of the
/// contact's effective mass (mass_bound; so for an upper bound of omega), the implicit one
/// elsewhere (a light body, an arm that spins a free wheel, no damper to make the row implicit).
struct SpringDamperRow {
  double erp = 0.0, cfm = 0.0;
  bool explicit_spring = false;
};
constexpr double kMaxExplicitOmegaH = 1.5;  // 25 % below symplectic Euler's limit of 2
SpringDamperRow spring_damper_row(double stiffness, double damping, double h, double mass_bound);

/// Whether a cylinder (centre c, unit axis u, radius r, half length hl: a wheel) and a box (centre
/// b, rotation rb whose columns are its axes, half sizes e: a rock) are disjoint, by exact
/// separating-axis tests, each of which proves it: the box's three face normals, the cylinder's
/// axis, and the direction from the box's point nearest c to c (the box lies behind the plane
/// through that point; the cylinder reaches at most r sqrt(1 - (n.u)^2) + hl |n.u| towards it,
/// within its bounding sphere). A gap must exceed kDisjointMargin so that a pair ODE's collider
/// would find just touching (rounding) is left to it. False means "may touch": the broad phase
/// (prepare_obstacles) calls ODE's dCollideCylinderBox only then (10.9k instructions a call).
constexpr double kDisjointMargin = 1e-9;  // [m]
bool cylinder_box_disjoint(const Eigen::Vector3d& c, const Eigen::Vector3d& u, double r, double hl,
                           const Eigen::Vector3d& b, const Eigen::Matrix3d& rb,
                           const Eigen::Vector3d& e);

/// The exact contact of a wheel (cylinder) and a rock (box) as the dContactGeom that
/// merge_contact_points(dCollide(cylinder, box, ...)) gives: g1 the cylinder, normal from the box
/// into it, sides -1 (SimOptions::wheel_obstacle_contact = Exact).
dContactGeom to_contact_geom(const CylinderBoxContact& c, dGeomID cylinder, dGeomID box);

}  // namespace ernest::dynamics::detail
