// Internal to cpp/dynamics: the one contact between a wheel (a cylinder) and a rock (a box) that
// the obstacle contacts use (seed 004 §3.4: one spring–damper per wheel–obstacle pair), computed
// directly: the exact penetration depth and its normal by the separating-axis theorem over the
// complete candidate set of a cylinder–box pair, and a contact point that is the depth-weighted
// centre of the deepest features (what merge_contact_points makes of ODE's clipped points).
// SimOptions::wheel_obstacle_contact chooses it (Exact) or ODE's dCollideCylinderBox (Ode).
#pragma once

#include <Eigen/Core>

namespace ernest::dynamics::detail {

/// The merged contact of a cylinder against a box, with the sign conventions of
/// merge_contact_points(dCollide(cylinder, box, ...)): normal points from the box into the
/// cylinder (moving the cylinder by depth * normal separates the shapes), depth >= 0, pos a point
/// of the cylinder inside the box (ODE's clipped points are the cylinder's).
struct CylinderBoxContact {
  double depth = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Vector3d pos = Eigen::Vector3d::Zero();
  int axis = -1;  ///< which candidate set gave the normal (CylinderBoxAxis), for tests and profiles
};

/// The candidate directions of the separating-axis theorem for a cylinder and a box. The
/// penetration depth is min over unit n of the overlap h_B(n) + h_A(-n) (h the support functions);
/// its minimiser is the normal of a smooth patch of the Minkowski difference B - A (an interior
/// point's nearest boundary point has a single normal), and the patches of a cylinder against a
/// box are: box face + cylinder point (Face), cap disc + box vertex (Cap), generator + box edge
/// (the cylinder axis x the edge: Cross), generator + box vertex (normal from the axis to the
/// vertex: Vertex), rim circle + box edge (an elliptic cylinder: RimEdge, a 1-D minimisation).
enum CylinderBoxAxis : int { Face = 0, Cap = 1, Cross = 2, Vertex = 3, RimEdge = 4 };

/// The contact between a cylinder (centre c, unit axis u, radius r, half length hl) and a box
/// (centre b, rotation rb whose columns are its axes, half sizes e). False (out untouched) where
/// an axis separates them: exactly where they are disjoint. No allocation.
bool cylinder_box_contact(const Eigen::Vector3d& c, const Eigen::Vector3d& u, double r, double hl,
                          const Eigen::Vector3d& b, const Eigen::Matrix3d& rb,
                          const Eigen::Vector3d& e, CylinderBoxContact& out);

/// The overlap h_B(n) + h_A(-n) along a unit direction n (box frame quantities: q the cylinder's
/// centre, a its axis): exported for the tests' brute-force minimum over the sphere.
double cylinder_box_overlap(const Eigen::Vector3d& n, const Eigen::Vector3d& q,
                            const Eigen::Vector3d& a, double r, double hl,
                            const Eigen::Vector3d& e);

}  // namespace ernest::dynamics::detail
