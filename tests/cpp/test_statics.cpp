// Tests of cpp/statics stability and force distribution (seed 003 §3.3, §5.1.1) against closed
// forms (rectangles, regular polygons, a tilted plane), Boost.Geometry (hulls and polygon
// intersections computed independently) and an explicit 6 x 3N pseudo-inverse.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <boost/geometry.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "ernest/statics/force_distribution.hpp"
#include "ernest/statics/stability.hpp"
#include "test_util.hpp"

using namespace ernest::statics;
using ernest::testing::invalid_argument_message;

namespace {
namespace bg = boost::geometry;
using BPoint = bg::model::d2::point_xy<double>;
using BPolygon = bg::model::polygon<BPoint>;

const Eigen::Vector3d kDown{0.0, 0.0, -9.81};

Eigen::Matrix3Xd rectangle(double a, double b) {
  Eigen::Matrix3Xd p(3, 4);
  p << a, -a, -a, a, b, b, -b, -b, 0, 0, 0, 0;
  return p;
}

Eigen::Matrix3Xd regular(int n, double radius, double phase = 0.0) {
  Eigen::Matrix3Xd p(3, n);
  for (int i = 0; i < n; ++i) {
    const double t = phase + 2.0 * M_PI * i / n;
    p.col(i) << radius * std::cos(t), radius * std::sin(t), 0.0;
  }
  return p;
}

bool no_nan(const StabilityMargins& m) {
  return !std::isnan(m.ssm) && !std::isnan(m.nesm) && !std::isnan(m.ssm_cps) &&
         !std::isnan(m.nesm_cps);
}

BPolygon boost_hull(const Eigen::Matrix3Xd& p, int skip = -1) {
  bg::model::multi_point<BPoint> mp;
  for (int i = 0; i < p.cols(); ++i) {
    if (i != skip) mp.push_back(BPoint(p(0, i), p(1, i)));
  }
  BPolygon hull;
  bg::convex_hull(mp, hull);
  return hull;
}
}  // namespace

TEST(Stability, RectangleClosedForm) {
  const double a = 1.2, b = 0.8, H = 1.75;
  const Eigen::Matrix3Xd feet = rectangle(a, b);
  for (const Eigen::Vector2d& c : {Eigen::Vector2d(0, 0), Eigen::Vector2d(0.3, -0.1),
                                  Eigen::Vector2d(-0.9, 0.5)}) {
    const StabilityMargins m = stability_margins(feet, {c.x(), c.y(), H}, kDown);
    const double d = std::min(a - std::abs(c.x()), b - std::abs(c.y()));
    EXPECT_EQ(m.support_vertices, 4);
    EXPECT_NEAR(m.ssm, d, 1e-12);
    // Flat ground: every axis horizontal, h = sqrt(d^2 + H^2) - H, smallest for the nearest edge.
    EXPECT_NEAR(m.nesm, std::hypot(d, H) - H, 1e-12);
    // The CPS of a rectangle is its centre (the four triangles share only that point).
    EXPECT_EQ(m.cps_vertices, 1);
    EXPECT_NEAR(m.ssm_cps, -c.norm(), 1e-12);
    EXPECT_LE(m.nesm_cps, 1e-12);
  }
  const ProjectionFrame frame = ProjectionFrame::from_gravity(kDown);
  EXPECT_NEAR(support_polygon(feet, frame).area(), 4 * a * b, 1e-12);
}

TEST(Stability, RegularPolygonsClosedForm) {
  // Regular n-gon of radius rho: SSM = apothem rho cos(pi/n); removing one vertex cuts the chord
  // through its two neighbours at distance rho cos(2 pi/n), so the CPS is the regular n-gon of
  // that apothem.
  const double rho = 2.0, H = 1.5;
  for (int n = 5; n <= 10; ++n) {
    const Eigen::Matrix3Xd feet = regular(n, rho, 0.3);
    const StabilityMargins m = stability_margins(feet, {0, 0, H}, kDown);
    const double ap = rho * std::cos(M_PI / n), ap_cps = rho * std::cos(2 * M_PI / n);
    EXPECT_EQ(m.support_vertices, n);
    EXPECT_EQ(m.cps_vertices, n) << n;
    EXPECT_NEAR(m.ssm, ap, 1e-12);
    EXPECT_NEAR(m.ssm_cps, ap_cps, 1e-12) << n;
    EXPECT_NEAR(m.nesm, std::hypot(ap, H) - H, 1e-12);
    EXPECT_NEAR(m.nesm_cps, std::hypot(ap_cps, H) - H, 1e-12);
    const Polygon cps = conservative_support_polygon(feet, ProjectionFrame::from_gravity(kDown));
    EXPECT_NEAR(cps.area(), n * ap_cps * ap_cps * std::tan(M_PI / n), 1e-11);
  }
}

TEST(Stability, TiltedPlaneClosedForm) {
  // A rectangle of feet on a plane rising at alpha along x, the CG at H along the plane normal
  // above its centre. Projected along vertical gravity the downhill edge is a cos(alpha) from the
  // centre and the CG is H sin(alpha) downhill. NESM: the downhill axis is horizontal,
  // h = sqrt(a^2 + H^2) - (a sin(alpha) + H cos(alpha)); the side axes are inclined by alpha,
  // h = cos(alpha) (sqrt(b^2 + H^2) - H).
  const double a = 1.0, b = 0.9, H = 1.2;
  for (double alpha : {0.0, 0.1, 0.25, 0.4}) {
    const Eigen::Vector3d xp{std::cos(alpha), 0, std::sin(alpha)}, yp{0, 1, 0},
        zp{-std::sin(alpha), 0, std::cos(alpha)};
    Eigen::Matrix3Xd feet(3, 4);
    const double sx[] = {1, -1, -1, 1}, sy[] = {1, 1, -1, -1};
    for (int i = 0; i < 4; ++i) feet.col(i) = sx[i] * a * xp + sy[i] * b * yp;
    const Eigen::Vector3d cg = H * zp;
    const StabilityMargins m = stability_margins(feet, cg, kDown);
    EXPECT_NEAR(m.ssm, std::min(a * std::cos(alpha) - H * std::sin(alpha), b), 1e-12);
    const double down = std::hypot(a, H) - (a * std::sin(alpha) + H * std::cos(alpha));
    const double side = std::cos(alpha) * (std::hypot(b, H) - H);
    EXPECT_NEAR(m.nesm, std::min(down, side), 1e-12) << alpha;
  }
}

TEST(Stability, NesmEdgeMatchesHiroseAngleForm) {
  // Hirose et al. (2001): h = |R| (1 - cos(theta)) cos(psi) + |R| sin(theta) sin(psi), theta the
  // angle of R from the vertical plane of the axis, psi the axis inclination; this form is the
  // same number for an inclined axis when theta is measured in the plane normal to the axis.
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d a{0, 0, 0}, b{2.0, 0.0, 0.6}, cg{0.7, 0.9, 1.4};
  const Eigen::Vector3d e = (b - a).normalized();
  const Eigen::Vector3d R = (cg - a) - (cg - a).dot(e) * e;
  const Eigen::Vector3d u = (up - up.dot(e) * e).normalized();  // in-plane "up" normal to axis
  const double psi = std::asin(e.dot(up)), theta = std::acos(R.normalized().dot(u));
  // Rising to the apex of the circle: |R| cos(psi) (1 - cos(theta)) in height.
  const double hirose = R.norm() * (1 - std::cos(theta)) * std::cos(psi);
  EXPECT_NEAR(nesm_edge(a, b, cg, up, true), hirose, 1e-12);
  EXPECT_NEAR(nesm_edge(a, b, cg, up, false), -hirose, 1e-12);
}

TEST(Stability, DegenerateCasesAreDefined) {
  const Eigen::Vector3d cg{0.2, 0.3, 1.0};
  // No contacts: no support at all.
  StabilityMargins m = stability_margins(Eigen::Matrix3Xd(3, 0), cg, kDown);
  EXPECT_EQ(m.support_vertices, 0);
  EXPECT_TRUE(std::isinf(m.ssm) && m.ssm < 0);
  EXPECT_TRUE(std::isinf(m.nesm_cps) && m.nesm_cps < 0);
  // One contact: minus the horizontal distance, and the pendulum drop.
  Eigen::Matrix3Xd one(3, 1);
  one << 0, 0, 0;
  m = stability_margins(one, cg, kDown);
  EXPECT_NEAR(m.ssm, -std::hypot(0.2, 0.3), 1e-12);
  EXPECT_NEAR(m.nesm, -(cg.norm() - cg.z()), 1e-12);
  // Collinear feet (three on the x axis): a segment; minus the distance to it.
  Eigen::Matrix3Xd line(3, 3);
  line << -1, 0, 1, 0, 0, 0, 0, 0, 0;
  m = stability_margins(line, cg, kDown);
  EXPECT_EQ(m.support_vertices, 2);
  EXPECT_NEAR(m.ssm, -0.3, 1e-12);
  EXPECT_NEAR(m.nesm, -(std::hypot(0.3, 1.0) - 1.0), 1e-12);
  m = stability_margins(line, {0.5, 0.0, 1.0}, kDown);
  EXPECT_NEAR(m.ssm, 0.0, 1e-12);
  EXPECT_NEAR(m.nesm, 0.0, 1e-12);
  // Three feet: the CPS is empty.
  m = stability_margins(regular(3, 1.0), {0, 0, 1}, kDown);
  EXPECT_EQ(m.cps_vertices, 0);
  EXPECT_NEAR(m.ssm, 0.5, 1e-12);
  EXPECT_TRUE(std::isinf(m.ssm_cps) && m.ssm_cps < 0);
  // CG outside: negative distance to the nearest edge, NESM negative.
  m = stability_margins(rectangle(1, 1), {3, 0.5, 1}, kDown);
  EXPECT_NEAR(m.ssm, -2.0, 1e-12);
  EXPECT_LT(m.nesm, 0.0);
  EXPECT_TRUE(no_nan(m));
  // Coincident feet count once.
  Eigen::Matrix3Xd dup(3, 5);
  dup << 1, -1, -1, 1, 1, 1, 1, -1, -1, -1, 0, 0, 0, 0, 0;
  EXPECT_EQ(stability_margins(dup, {0, 0, 1}, kDown).support_vertices, 4);
}

TEST(Stability, RandomStancesAgreeWithBoostGeometry) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-2.0, 2.0), z(-0.3, 0.3);
  const ProjectionFrame frame = ProjectionFrame::from_gravity(kDown);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 4 + trial % 5;
    Eigen::Matrix3Xd feet(3, n);
    for (int i = 0; i < n; ++i) feet.col(i) << u(rng), u(rng), z(rng);
    const Polygon hull = support_polygon(feet, frame);
    EXPECT_NEAR(hull.area(), bg::area(boost_hull(feet)), 1e-9);
    // CPS: intersect the n hulls-minus-one with Boost.Geometry.
    std::vector<BPolygon> acc{boost_hull(feet, 0)};
    for (int k = 1; k < n && !acc.empty(); ++k) {
      std::vector<BPolygon> next;
      for (const BPolygon& p : acc) bg::intersection(p, boost_hull(feet, k), next);
      acc = next;
    }
    double area = 0.0;
    for (const BPolygon& p : acc) area += bg::area(p);
    // Boost 1.74 intersects on a rescaled integer grid (its robustness policy; without it the
    // shared edges of these hulls break it), which costs ~1e-7 in area: hence 1e-6 here, and
    // the exact check that every CPS vertex lies in every hull-minus-one.
    const Polygon cps = conservative_support_polygon(feet, frame);
    EXPECT_NEAR(cps.area(), area, 1e-6) << trial;
    for (int k = 0; k < n; ++k) {
      Eigen::Matrix3Xd rest(3, n - 1);
      for (int i = 0, c = 0; i < n; ++i) {
        if (i != k) rest.col(c++) = feet.col(i);
      }
      const Polygon sub = support_polygon(rest, frame);
      for (int v = 0; v < cps.size; ++v) EXPECT_GE(sub.signed_distance(cps.vertices[v]), -1e-12);
    }
    const Eigen::Vector3d cg{0.5 * u(rng), 0.5 * u(rng), 1.0};
    const StabilityMargins m = stability_margins(feet, cg, kDown);
    EXPECT_TRUE(no_nan(m));
    const bool inside = bg::within(BPoint(cg.x(), cg.y()), boost_hull(feet));
    EXPECT_EQ(m.ssm > 0, inside);
    EXPECT_EQ(m.nesm > 0, inside);
    EXPECT_LE(m.ssm_cps, m.ssm + 1e-12);  // the CPS lies inside the support polygon
  }
}

TEST(Stability, InvalidInputNamesTheField) {
  Eigen::Matrix3Xd feet = rectangle(1, 1);
  feet(2, 1) = std::nan("");
  EXPECT_NE(invalid_argument_message([&] { stability_margins(feet, {0, 0, 1}, kDown); })
                .find("contacts"),
            std::string::npos);
  EXPECT_NE(invalid_argument_message(
                [&] { stability_margins(rectangle(1, 1), {0, 0, 1}, Eigen::Vector3d::Zero()); })
                .find("gravity"),
            std::string::npos);
  EXPECT_NE(invalid_argument_message(
                [&] { stability_margins(rectangle(1, 1), {0, NAN, 1}, kDown); })
                .find("cg"),
            std::string::npos);
  EXPECT_NE(invalid_argument_message(
                [&] { stability_margins(Eigen::Matrix3Xd::Zero(3, 17), {0, 0, 1}, kDown); })
                .find("contacts"),
            std::string::npos);
}

namespace {
Eigen::MatrixXd equilibrium_matrix(const Eigen::Matrix3Xd& p) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(6, 3 * p.cols());
  for (int i = 0; i < p.cols(); ++i) {
    A.block<3, 3>(0, 3 * i).setIdentity();
    A.block<3, 3>(3, 3 * i) << 0, -p(2, i), p(1, i), p(2, i), 0, -p(0, i), -p(1, i), p(0, i), 0;
  }
  return A;
}
}  // namespace

TEST(ForceDistribution, EquilibriumAndZeroInteractionOnRandomStances) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-2.0, 2.0), z(-0.5, 0.5);
  const double mass = 850.0;
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 3 + trial % 6;
    Eigen::Matrix3Xd feet(3, n);
    for (int i = 0; i < n; ++i) feet.col(i) << u(rng), u(rng), z(rng);
    const Eigen::Vector3d cg{0.5 * u(rng), 0.5 * u(rng), 1.5 + z(rng)};
    const Eigen::Vector3d g = Eigen::Vector3d(0.1 * u(rng), 0.1 * u(rng), -9.81);
    DistributionInfo info;
    const Eigen::Matrix3Xd f = zero_interaction_forces(feet, cg, mass, g, &info);
    EXPECT_EQ(info.rank, 6);
    EXPECT_LT(info.residual, 1e-13);
    // Equilibrium, independently: forces and moments about the world origin.
    Eigen::Vector3d sf = mass * g, sm = cg.cross(mass * g);
    for (int i = 0; i < n; ++i) {
      sf += f.col(i);
      sm += Eigen::Vector3d(feet.col(i)).cross(Eigen::Vector3d(f.col(i)));
    }
    EXPECT_LT(sf.norm(), 1e-9 * mass * 9.81);
    EXPECT_LT(sm.norm(), 1e-9 * mass * 9.81 * 3.0);
    // Zero interaction: for every pair, equal projections on the line joining them.
    for (int i = 0; i < n; ++i) {
      for (int j = i + 1; j < n; ++j) {
        const Eigen::Vector3d l = (feet.col(i) - feet.col(j)).normalized();
        EXPECT_NEAR(l.dot(f.col(i)), l.dot(f.col(j)), 1e-9 * mass * 9.81);
      }
    }
    // The explicit pseudo-inverse of the 6 x 3N system gives the same forces.
    Eigen::VectorXd w(6);
    w << -mass * g, -cg.cross(mass * g);
    const Eigen::VectorXd ref =
        equilibrium_matrix(feet).completeOrthogonalDecomposition().pseudoInverse() * w;
    EXPECT_LT((Eigen::Map<const Eigen::VectorXd>(f.data(), 3 * n) - ref).norm(),
              1e-9 * mass * 9.81);
  }
}

TEST(ForceDistribution, SymmetricAndDegenerateStances) {
  const double mass = 100.0;
  const Eigen::Matrix3Xd f = zero_interaction_forces(rectangle(1, 0.5), {0, 0, 1}, mass, kDown);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(f(2, i), mass * 9.81 / 4, 1e-10);
    EXPECT_NEAR(f.col(i).head<2>().norm(), 0.0, 1e-10);
  }
  // Collinear feet: no moment about their line (rank 5). CG above the line: balanced.
  Eigen::Matrix3Xd line(3, 3);
  line << -1, 0, 1, 0, 0, 0, 0, 0, 0;
  DistributionInfo info;
  zero_interaction_forces(line, {0.3, 0, 1}, mass, kDown, &info);
  EXPECT_EQ(info.rank, 5);
  EXPECT_LT(info.residual, 1e-13);
  const Eigen::Matrix3Xd fl = zero_interaction_forces(line, {0.3, 0.2, 1}, mass, kDown, &info);
  EXPECT_GT(info.residual, 0.05);
  EXPECT_TRUE(fl.allFinite());
  // One foot and none: defined.
  zero_interaction_forces(line.leftCols(1), {0.3, 0.2, 1}, mass, kDown, &info);
  EXPECT_EQ(info.rank, 3);
  EXPECT_GT(info.residual, 0.0);
  const Eigen::Matrix3Xd none = zero_interaction_forces(Eigen::Matrix3Xd(3, 0), {0, 0, 1}, mass,
                                                        kDown, &info);
  EXPECT_EQ(none.cols(), 0);
  EXPECT_EQ(info.rank, 0);
  EXPECT_NE(invalid_argument_message(
                [&] { zero_interaction_forces(line, {0, 0, 1}, -1.0, kDown); })
                .find("mass"),
            std::string::npos);
}
