// The exact wheel–rock contact (cpp/dynamics/cylinder_box.hpp) against closed forms (a wheel
// level on a box top, against a vertical face, tilted onto its rim, a box edge under and across
// the tread, a box corner into the cap near the rim), symmetry (mirroring the pose mirrors the
// contact), continuity under small pose changes, disjoint poses, and the depth as the minimum of
// the overlap over the whole sphere (dense directions refined by local search: no direction beats
// the normal). Against ODE's collider: test_dynamics_cylinder_box_ode.cpp.
#include <gtest/gtest.h>
#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cylinder_box_poses.hpp"
#include "ernest/dynamics/cylinder_box.hpp"
#include "ernest/dynamics/obstacle_contacts.hpp"

using namespace ernest::dynamics;
using namespace cylinder_box_poses;

namespace {

TEST(CylinderBox, WheelLevelOnBoxTop) {
  const Vec3 e(0.3, 0.3, 0.1);
  CylinderBoxContact k;
  ASSERT_TRUE(contact(Vec3(0.05, 0.0, 0.1 + kR - 0.01), kY, Vec3::Zero(), Mat3::Identity(), e, k));
  EXPECT_NEAR(k.depth, 0.01, 1e-14);
  EXPECT_NEAR((k.normal - Vec3::UnitZ()).norm(), 0.0, 1e-14);
  EXPECT_NEAR((k.pos - Vec3(0.05, 0.0, 0.09)).norm(), 0.0, 1e-14);
  EXPECT_EQ(k.axis, detail::Face);
  // Half over the box's side at y = 0.3: the contact line clipped to the face, at its middle
  ASSERT_TRUE(contact(Vec3(0.05, 0.28, 0.1 + kR - 0.01), kY, Vec3::Zero(), Mat3::Identity(), e, k));
  EXPECT_NEAR(k.depth, 0.01, 1e-14);
  EXPECT_NEAR((k.pos - Vec3(0.05, 0.5 * (0.28 - kHl + 0.3), 0.09)).norm(), 0.0, 1e-14);
  // The same with the box moved and yawed: the contact moves with it
  const Mat3 yaw = rot(0.7, Vec3::UnitZ());
  const Vec3 b(1.0, -2.0, 0.5);
  ASSERT_TRUE(contact(b + yaw * Vec3(0.05, 0.28, 0.1 + kR - 0.01), yaw * kY, b, yaw, e, k));
  EXPECT_NEAR(k.depth, 0.01, 1e-14);
  EXPECT_NEAR((k.pos - (b + yaw * Vec3(0.05, 0.5 * (0.28 - kHl + 0.3), 0.09))).norm(), 0.0, 1e-14);
}

TEST(CylinderBox, WheelAgainstVerticalFace) {
  const Vec3 e(0.3, 0.3, 0.2);
  CylinderBoxContact k;
  ASSERT_TRUE(contact(Vec3(0.3 + kR - 0.02, 0.0, 0.05), kY, Vec3::Zero(), Mat3::Identity(), e, k));
  EXPECT_NEAR(k.depth, 0.02, 1e-14);
  EXPECT_NEAR((k.normal - Vec3::UnitX()).norm(), 0.0, 1e-14);
  EXPECT_NEAR((k.pos - Vec3(0.28, 0.0, 0.05)).norm(), 0.0, 1e-14);  // at the axle's height
}

// Tilted by 0.3 rad about x, the wheel touches the top at its lowest rim point only: the depth
// of that point (r cos t + hl sin t below the centre) and the point itself (the generator's
// clipped part has depth 0 where it leaves the face: all the weight at the rim).
TEST(CylinderBox, RimOnFaceWithWheelTilted) {
  const Vec3 e(0.3, 0.3, 0.1), u(0.0, std::cos(0.3), std::sin(0.3));
  const double low = kR * std::cos(0.3) + kHl * std::sin(0.3);
  const Vec3 c(0.02, 0.01, 0.1 + low - 0.004);
  CylinderBoxContact k;
  ASSERT_TRUE(contact(c, u, Vec3::Zero(), Mat3::Identity(), e, k));
  EXPECT_NEAR(k.depth, 0.004, 1e-14);
  EXPECT_NEAR((k.normal - Vec3::UnitZ()).norm(), 0.0, 1e-14);
  const Vec3 down = -(Vec3::UnitZ() - u.z() * u).normalized();
  EXPECT_NEAR((k.pos - (c + kR * down - kHl * u)).norm(), 0.0, 1e-12);
}

// A box edge (a box turned 45 deg about x, its ridge along x at z = 0.1 sqrt 2) under a wheel
// whose axle is along x: generator against edge, normal a x e = +z, the contact at the ridge.
// And a step edge parallel to the axle: normal from the edge to the axle, depth r - distance.
TEST(CylinderBox, BoxEdgeIntoTread) {
  const Vec3 e(0.3, 0.1, 0.1);
  const Mat3 rb = rot(M_PI / 4, Vec3::UnitX());
  const double ridge = 0.1 * std::sqrt(2.0);
  CylinderBoxContact k;
  ASSERT_TRUE(contact(Vec3(0.0, 0.0, ridge + kR - 0.01), rot(0.4, Vec3::UnitZ()) * kY,
                      Vec3::Zero(), rb, e, k));
  EXPECT_NEAR(k.depth, 0.01, 1e-14);
  EXPECT_NEAR((k.normal - Vec3::UnitZ()).norm(), 0.0, 1e-14);
  EXPECT_EQ(k.axis, detail::Cross);
  EXPECT_NEAR((k.pos - Vec3(0.0, 0.0, ridge - 0.01)).norm(), 0.0, 1e-14);
  // the edge at (y, z) = (0.3, 0.1) of a box under a wheel rolling onto it along -y
  const Vec3 e2(0.5, 0.3, 0.1), edge(0.0, 0.3, 0.1), dir = Vec3(0.0, 0.6, 0.8);
  const Vec3 c = edge + (kR - 0.007) * dir;  // axle at kR - 7 mm from the edge
  ASSERT_TRUE(contact(c, Vec3::UnitX(), Vec3::Zero(), Mat3::Identity(), e2, k));
  EXPECT_NEAR(k.depth, 0.007, 1e-14);
  EXPECT_NEAR((k.normal - dir).norm(), 0.0, 1e-14);
  EXPECT_EQ(k.axis, detail::Vertex);
  // the generator nearest the edge, clipped to the box: its middle, inside the edge
  const Vec3 g = c - kR * dir;
  EXPECT_NEAR(k.pos.x(), 0.0, 1e-14);
  EXPECT_NEAR((k.pos - g).norm(), 0.0, 1e-12);
}

// A box corner pointing straight down (its diagonal along -z) into the wheel's cap (axis z)
// near the rim: the corner's depth below the cap, normal -z, the point under the corner (the
// corner's section by the cap plane is a triangle centred under it, all at the same depth).
TEST(CylinderBox, BoxCornerIntoCapNearRim) {
  const Vec3 e(0.05, 0.05, 0.05);
  const Mat3 rb = Eigen::Quaterniond::FromTwoVectors(Vec3(1, 1, 1).normalized(), -Vec3::UnitZ())
                      .toRotationMatrix();
  const double corner = 0.05 * std::sqrt(3.0);
  const Vec3 v(0.15, 0.02, kHl - 0.004);  // the corner, 4 mm into the cap, 0.151 m off the axis
  const Vec3 b = v + corner * Vec3::UnitZ();
  CylinderBoxContact k;
  ASSERT_TRUE(contact(Vec3::Zero(), Vec3::UnitZ(), b, rb, e, k));
  EXPECT_NEAR(k.depth, 0.004, 1e-14);
  EXPECT_NEAR((k.normal + Vec3::UnitZ()).norm(), 0.0, 1e-14);
  EXPECT_EQ(k.axis, detail::Cap);
  EXPECT_NEAR((k.pos - Vec3(v.x(), v.y(), kHl)).norm(), 0.0, 1e-12);
}

// A local search on the sphere from n (16 directions turning by a golden angle each try; steps
// halving to 1e-9 rad).
void descend(const Pose& p, Vec3& best_n, double& best) {
  double turn = 0.0;
  for (double step = 0.02; step > 1e-9; step *= 0.5) {
    bool improved = true;
    while (improved) {
      improved = false;
      const Vec3 t1 = best_n.unitOrthogonal(), t2 = best_n.cross(t1);
      turn += 2.39996322972865332;
      for (int s = 0; s < 16; ++s) {
        const double ang = turn + s * M_PI / 8;
        const Vec3 n = (best_n + step * (std::cos(ang) * t1 + std::sin(ang) * t2)).normalized();
        const double d = overlap(p, n);
        if (d < best) best = d, best_n = n, improved = true;
      }
    }
  }
}

// The least overlap found by brute force: 10000 spread directions (a Fibonacci sphere) refined by
// a local search, and, since the overlap has kinks along the great circles where a term |n.x|
// vanishes (n normal to a box axis or to the cylinder's axis) and its minimum often lies on one
// (a V-shaped valley that a local search on the sphere stalls in), 10000 directions along each of
// these circles refined by golden-section search; and the cone points +-u of |n x u|. An upper
// bound of the true minimum.
double brute_min(const Pose& p) {
  constexpr int kN = 10000;
  Vec3 best_n = Vec3::UnitZ();
  double best = HUGE_VAL;
  for (int k = 0; k < kN; ++k) {
    const double z = 1.0 - (2.0 * k + 1.0) / kN, rho = std::sqrt(1.0 - z * z);
    const double phi = k * 2.39996322972865332;
    const Vec3 n(rho * std::cos(phi), rho * std::sin(phi), z);
    const double d = overlap(p, n);
    if (d < best) best = d, best_n = n;
  }
  descend(p, best_n, best);
  for (double sign : {1.0, -1.0}) best = std::min(best, overlap(p, sign * p.u));  // |n x u|'s cone
  for (int c = 0; c < 4; ++c) {
    const Vec3 axis = c < 3 ? Vec3(p.rb.col(c)) : p.u;
    const Vec3 t1 = axis.unitOrthogonal(), t2 = axis.cross(t1);
    const auto at = [&](double phi) { return overlap(p, std::cos(phi) * t1 + std::sin(phi) * t2); };
    const double step = 2.0 * M_PI / kN;
    double best_phi = 0.0, best_c = HUGE_VAL;
    for (int k = 0; k < kN; ++k)
      if (at(k * step) < best_c) best_c = at(k * step), best_phi = k * step;
    double lo = best_phi - step, hi = best_phi + step;  // golden section on the bracket
    for (int it = 0; it < 60; ++it) {
      const double m1 = hi - 0.618033988749895 * (hi - lo), m2 = lo + 0.618033988749895 * (hi - lo);
      if (at(m1) < at(m2)) hi = m2; else lo = m1;
    }
    best = std::min({best, best_c, at(0.5 * (lo + hi))});
  }
  return best;
}

// Exactness: over 400 random poses (any orientation), no direction has a smaller overlap than
// the contact's normal, and a contact is returned exactly where the minimum overlap is >= 0.
TEST(CylinderBox, DepthIsTheMinimumOverTheSphere) {
  std::mt19937 rng(7);
  int touching = 0, by_axis[5] = {};
  double worst = 0.0;  // how far above the brute force ends
  for (int trial = 0; trial < 400; ++trial) {
    const Pose p = random_pose(rng, true);
    CylinderBoxContact k;
    const bool hit = contact(p.c, p.u, p.b, p.rb, p.e, k);
    const double brute = brute_min(p);
    if (!hit) {
      EXPECT_LT(brute, 1e-12) << trial;  // some direction separates
      EXPECT_TRUE(detail::cylinder_box_disjoint(p.c, p.u, kR, kHl, p.b, p.rb, p.e) ||
                  brute < 0.0);
      continue;
    }
    ++touching;
    ++by_axis[k.axis];
    EXPECT_GE(brute, k.depth - 1e-12) << trial << " axis " << k.axis;
    EXPECT_NEAR(overlap(p, k.normal), k.depth, 1e-12);
    EXPECT_NEAR(k.normal.norm(), 1.0, 1e-12);
    EXPECT_GE(k.depth, 0.0);
    worst = std::max(worst, brute - k.depth);
  }
  std::printf("touching %d of 400: face %d cap %d cross %d vertex %d rim-edge %d; brute force "
              "above by at most %.2e m\n", touching, by_axis[0], by_axis[1], by_axis[2], by_axis[3],
              by_axis[4], worst);
  EXPECT_LT(worst, 1e-9);
  EXPECT_GT(touching, 120);
  EXPECT_GT(by_axis[detail::RimEdge], 20);  // the 1-D minimisation is exercised
}

// Mirroring the whole pose in the plane x = 0 mirrors the contact (depth equal, normal and
// point mirrored); reversing the cylinder's axis changes nothing.
TEST(CylinderBox, MirrorAndAxisReversal) {
  std::mt19937 rng(11);
  const Mat3 mirror = Eigen::Vector3d(-1, 1, 1).asDiagonal();
  int checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Pose p = random_pose(rng, true);
    CylinderBoxContact k, km, kr;
    if (!contact(p.c, p.u, p.b, p.rb, p.e, k)) continue;
    // a mirrored box: its rotation times the mirror is a rotation again with one axis flipped
    const Mat3 rbm = mirror * p.rb * mirror;
    ASSERT_TRUE(contact(mirror * p.c, mirror * p.u, mirror * p.b, rbm, p.e, km));
    ASSERT_TRUE(contact(p.c, -p.u, p.b, p.rb, p.e, kr));
    EXPECT_NEAR(km.depth, k.depth, 1e-12);
    EXPECT_NEAR(kr.depth, k.depth, 1e-12);
    if (k.depth > 1e-6) {  // ties between axes aside, the same normal
      EXPECT_NEAR((km.normal - mirror * k.normal).norm(), 0.0, 1e-6) << trial;
      EXPECT_NEAR((kr.normal - k.normal).norm(), 0.0, 1e-6) << trial;
      EXPECT_NEAR((km.pos - mirror * k.pos).norm(), 0.0, 1e-6) << trial;
    }
    ++checked;
  }
  EXPECT_GT(checked, 700);
}

// Small pose changes (1e-7 m, 1e-7 rad) change the depth by at most about as much, and the normal
// by little except where two candidates tie (the minimum switches feature): over random poses,
// 99 % of normals move by < 1e-4.
TEST(CylinderBox, ContinuityUnderSmallPoseChanges) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  int n = 0, jumps = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Pose p = random_pose(rng, true);
    CylinderBoxContact k, k2;
    if (!contact(p.c, p.u, p.b, p.rb, p.e, k) || k.depth < 1e-5) continue;
    const Vec3 dc = 1e-7 * Vec3(uni(rng), uni(rng), uni(rng));
    const Vec3 u2 = rot(1e-7, Vec3(uni(rng), uni(rng), uni(rng))) * p.u;
    ASSERT_TRUE(contact(p.c + dc, u2, p.b, p.rb, p.e, k2));
    EXPECT_NEAR(k2.depth, k.depth, 1e-6) << trial;
    if ((k2.normal - k.normal).norm() > 1e-4) ++jumps;
    ++n;
  }
  EXPECT_GT(n, 500);
  EXPECT_LT(jumps, n / 100 + 1);
}

// Moved apart along the normal by the depth plus a little, the shapes are disjoint; by the depth
// minus a little they still touch.
TEST(CylinderBox, SeparatesAtTheDepth) {
  std::mt19937 rng(17);
  int n = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const Pose p = random_pose(rng, true);
    CylinderBoxContact k, k2;
    if (!contact(p.c, p.u, p.b, p.rb, p.e, k)) continue;
    EXPECT_FALSE(contact(p.c + (k.depth + 1e-9) * k.normal, p.u, p.b, p.rb, p.e, k2)) << trial;
    if (k.depth > 1e-8) {
      EXPECT_TRUE(contact(p.c + (k.depth - 1e-9) * k.normal, p.u, p.b, p.rb, p.e, k2)) << trial;
    }
    ++n;
  }
  EXPECT_GT(n, 300);
  CylinderBoxContact k;
  const Vec3 nan(std::nan(""), 0.0, 0.0);
  EXPECT_FALSE(contact(nan, kY, Vec3::Zero(), Mat3::Identity(), Vec3::Constant(0.1), k));
}

}  // namespace
