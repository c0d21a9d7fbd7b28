// Static stability of any set of ground contacts (seed 003 §3.3): the support polygon projected
// along gravity, the Conservative Polygon of Support (CPS), the Static Stability Margin (SSM) and
// Hirose's Normalized Energy Stability Margin (NESM). Robot-agnostic: the inputs are the contact
// positions, the centre of gravity and the gravity vector, all in one world frame [m].
//
// Conventions (every answer is defined; none is NaN):
//  * Polygons live in the 2-D frame (e1, e2) of ProjectionFrame, perpendicular to gravity, and are
//    counter-clockwise seen from "up" = -g/|g|. Each edge k (vertex k -> k+1) carries the indices
//    of the two contacts whose supporting line it lies on (the tipping axis of that edge).
//  * A polygon of n >= 3 vertices is proper; n = 2 is a segment (collinear contacts), n = 1 a
//    point, n = 0 empty (no contacts, or an empty CPS).
//  * SSM = signed distance of the projected CG to the polygon boundary: > 0 inside, < 0 outside;
//    for a segment or a point, minus the distance to it (0 on it); -inf for an empty polygon.
//  * NESM (metres: energy over m|g|), see nesm_edge() for the formula. Negative outside; for n < 3
//    the minimum over the edges of -|h| (n = 2; "balanced" only on the line), the inverted-pendulum
//    drop for n = 1, -inf for n = 0.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>

namespace ernest::statics {

/// Largest number of contacts the stability functions accept (fixed-capacity workspace, so the
/// hot path never allocates).
inline constexpr int kMaxContacts = 16;

/// Orthonormal frame with `up` = -g/|g|; (e1, e2, up) is right-handed.
struct ProjectionFrame {
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitX();
  Eigen::Vector3d e2 = Eigen::Vector3d::UnitY();

  /// Frame for a gravity vector (any non-zero finite vector; std::invalid_argument otherwise).
  /// For g along -z it is the world x, y, z frame.
  static ProjectionFrame from_gravity(const Eigen::Vector3d& gravity);
  /// Coordinates of p projected along gravity onto the (e1, e2) plane.
  Eigen::Vector2d project(const Eigen::Vector3d& p) const { return {e1.dot(p), e2.dot(p)}; }
};

/// Fixed-capacity convex polygon in the projection frame (see the conventions above).
struct Polygon {
  static constexpr int kCapacity = 128;
  int size = 0;
  std::array<Eigen::Vector2d, kCapacity> vertices;
  std::array<std::array<int, 2>, kCapacity> edge_contacts;  ///< contacts carrying edge k -> k+1

  Polygon() = default;
  // Copies only the used vertices (the arrays are a few kB).
  Polygon(const Polygon& o) { *this = o; }
  Polygon& operator=(const Polygon& o) {
    size = o.size;
    std::copy(o.vertices.begin(), o.vertices.begin() + size, vertices.begin());
    std::copy(o.edge_contacts.begin(), o.edge_contacts.begin() + size, edge_contacts.begin());
    return *this;
  }

  double area() const;
  /// Signed distance of point q to the boundary (the SSM convention above).
  double signed_distance(const Eigen::Vector2d& q) const;
  /// Vertices as a 2 x size matrix (allocates; for plotting and bindings).
  Eigen::Matrix2Xd vertex_matrix() const;
};

/// Convex hull of the contacts projected along gravity (§3.3 "support polygon"). Collinear
/// contacts on an edge are dropped; coincident ones count once.
Polygon support_polygon(const Eigen::Ref<const Eigen::Matrix3Xd>& contacts,
                        const ProjectionFrame& frame);

/// §3.3 CPS: the intersection of the support polygons of the contacts with each one contact
/// removed (one supporting leg may fail). Three contacts give an empty CPS; four at the corners
/// of a rectangle give its centre (a point).
Polygon conservative_support_polygon(const Eigen::Ref<const Eigen::Matrix3Xd>& contacts,
                                     const ProjectionFrame& frame);

/// Normalized energy stability level of one tipping axis through contacts a and b
/// (Hirose, Tsukagoshi and Yoneda 2001), in metres:
///   R = (c - a) - ((c - a).e) e,  e = (b - a)/|b - a|   (CG offset perpendicular to the axis)
///   h = |R| sqrt(1 - (e.up)^2) - R.up
/// i.e. |R| cos(psi) - |R| cos(theta) with psi the axis inclination and theta the angle of R from
/// the vertical plane of the axis: the height the CG must rise to turn over the axis, which is
/// Hirose's |R|(1 - cos theta) cos psi + |R| sin theta sin psi written without angles.
/// `inside` false (the CG's projection beyond the edge) returns -h, so the value is continuous
/// across the edge and negative once the robot is already tipping.
double nesm_edge(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& cg,
                 const Eigen::Vector3d& up, bool inside);

/// The margins of one stance.
struct StabilityMargins {
  int support_vertices = 0;  ///< vertices of the support polygon (n < 3: degenerate)
  int cps_vertices = 0;      ///< vertices of the CPS
  double ssm = 0.0;          ///< SSM w.r.t. the support polygon [m]
  double nesm = 0.0;         ///< NESM w.r.t. the support polygon [m]
  double ssm_cps = 0.0;      ///< SSM w.r.t. the CPS [m] (FootFall's criterion)
  double nesm_cps = 0.0;     ///< NESM w.r.t. the CPS [m]
};

/// SSM and NESM of a polygon built from `contacts` (edges labelled with contact indices).
double static_stability_margin(const Polygon& polygon, const Eigen::Vector3d& cg,
                               const ProjectionFrame& frame);
double energy_stability_margin(const Polygon& polygon,
                               const Eigen::Ref<const Eigen::Matrix3Xd>& contacts,
                               const Eigen::Vector3d& cg, const ProjectionFrame& frame);

/// All margins in one call (no allocation). Throws std::invalid_argument naming the field for
/// non-finite input, zero gravity or more than kMaxContacts contacts.
StabilityMargins stability_margins(const Eigen::Ref<const Eigen::Matrix3Xd>& contacts,
                                   const Eigen::Vector3d& cg, const Eigen::Vector3d& gravity);

}  // namespace ernest::statics
