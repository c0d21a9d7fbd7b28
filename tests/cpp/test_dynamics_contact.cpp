// Seed 004 §3.4's rigid contact (spring k = 20 kN/m, damper c = 20 N s/m) as the obstacle rows
// integrate it (cpp/dynamics/obstacle_contacts.hpp), on single bodies in a bare ODE world against
// closed forms: a 3 kg ball pressed into a box top oscillates at sqrt(k / m) with the damping
// ratio c / (2 sqrt(k m)) about the static deflection m g / k, at the default step and at a
// quarter of it; a light ball falls back to the implicit row, which is stable where the explicit
// spring is not; a wheel's points merged into one contact push it under its centre (on a box
// top) and at its axle's height (against a face), with the load and no torque. The broad phase's
// exact early-out for a wheel against a rock (cylinder_box_disjoint) against ODE's collider over
// random poses and against closed forms.
#include <gtest/gtest.h>
#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "ernest/dynamics/obstacle_contacts.hpp"
#include "ernest/solver/ode_init.hpp"
#include "ernest/dynamics/rover_sim.hpp"
#include "ernest/soil/rigid_contact.hpp"

using namespace ernest::dynamics;

namespace {

constexpr double kPi = 3.14159265358979323846;
const double kDt = SimOptions{}.dt;
const ernest::soil::RigidContactParameters kRigid{};

// A body (a ball, or a wheel: a cylinder with its axis along y) over a static box whose top is
// z = 0, spanning x in [-1, 1] (face at x = 1 for a push), and one merged contact per step.
struct Bench {
  dWorldID world;
  dSpaceID space;
  dJointGroupID group;
  dBodyID body;
  dGeomID geom, box;
  double mass;
  int points = 0;        // ODE's points in the last collision
  dJointFeedback fb{};   // the contact's force on the body
  dContactGeom merged{};
  bool force_explicit = false;

  Bench(double m, double radius, bool wheel, double gravity) : mass(m) {
    ernest::solver::init_ode_once();
    world = dWorldCreate();
    dWorldSetGravity(world, 0, 0, -gravity);
    space = dSimpleSpaceCreate(nullptr);
    group = dJointGroupCreate(0);
    body = dBodyCreate(world);
    dMass dm;
    if (wheel) {
      dMassSetCylinderTotal(&dm, m, 3, radius, RoverParameters{}.wheel_width);
      geom = dCreateCylinder(space, radius, RoverParameters{}.wheel_width);
    } else {
      dMassSetSphereTotal(&dm, m, radius);
      geom = dCreateSphere(space, radius);
    }
    dBodySetMass(body, &dm);
    dGeomSetBody(geom, body);
    if (wheel) {  // cylinder axis (local z) along world y
      dMatrix3 r;
      dRFromAxisAndAngle(r, 1, 0, 0, kPi / 2);
      dBodySetRotation(body, r);
    }
    box = dCreateBox(space, 2.0, 2.0, 2.0);
    dGeomSetPosition(box, 0.0, 0.0, -1.0);
  }
  ~Bench() {
    dJointGroupDestroy(group);
    dSpaceDestroy(space);
    dWorldDestroy(world);
  }

  void step(double h) {
    dContactGeom pts[4];
    points = dCollide(geom, box, 4, pts, sizeof(dContactGeom));
    if (points > 0) {
      dContact c{};
      c.geom = merged = detail::merge_contact_points(pts, points);
      const detail::SpringDamperRow r =
          force_explicit ? detail::SpringDamperRow{h * kRigid.stiffness / kRigid.damping,
                                                   1.0 / kRigid.damping, true}
                         : detail::spring_damper_row(kRigid.stiffness, kRigid.damping, h, mass);
      c.surface.mode = dContactSoftERP | dContactSoftCFM;  // frictionless: the normal row only
      c.surface.mu = 0.0;
      c.surface.soft_erp = r.erp;
      c.surface.soft_cfm = r.cfm;
      dJointID j = dJointCreateContact(world, group, &c);
      dJointAttach(j, body, nullptr);
      dJointSetFeedback(j, &fb);
    }
    dWorldStep(world, h);
    dJointGroupEmpty(group);
  }
  double z() const { return dBodyGetPosition(body)[2]; }
};

struct Oscillation {
  double period = 0.0, decay = 0.0, mean = 0.0;  // decay: amplitude ratio per period
};

// A 3 kg ball of radius 0.17 m pressed 1.5 static deflections into the box top and let go at
// rest: the deflection's period from its upward crossings of the closed-form static deflection,
// the decay from its mean square over the 2nd-3rd and the 8th-9th closed-form periods (many
// samples per window: the default step resolves a period with only 6), and the mean deflection
// over 2.9-3 s (decayed to below 1e-3 of the start).
Oscillation ball_oscillation(double h) {
  const double m = 3.0, r = 0.17, k = kRigid.stiffness, g = 9.81;
  const double xs = m * g / k, period = 2 * kPi / std::sqrt(k / m);
  Bench b(m, r, false, g);
  dBodySetPosition(b.body, 0.0, 0.0, r - 1.5 * xs);
  std::vector<double> t, e;
  const int n = static_cast<int>(std::lround(3.0 / h));
  for (int i = 1; i <= n; ++i) {
    b.step(h);
    t.push_back(i * h);
    e.push_back(r - b.z() - xs);
  }
  Oscillation o;
  std::vector<double> up;
  for (std::size_t i = 1; i < e.size() && t[i] < 0.8; ++i)
    if (e[i - 1] < 0.0 && e[i] >= 0.0) up.push_back(t[i] - h * e[i] / (e[i] - e[i - 1]));
  o.period = (up.back() - up.front()) / static_cast<double>(up.size() - 1);
  const auto mean_square = [&](double t0, double t1) {
    double s = 0.0;
    int c = 0;
    for (std::size_t i = 0; i < e.size(); ++i)
      if (t[i] >= t0 && t[i] < t1) s += e[i] * e[i], ++c;
    return s / c;
  };
  o.decay = std::pow(mean_square(7 * period, 9 * period) / mean_square(period, 3 * period),
                     1.0 / 12.0);
  double s = 0.0;
  int c = 0;
  for (std::size_t i = 0; i < e.size(); ++i)
    if (t[i] >= 2.9) s += e[i] + xs, ++c;
  o.mean = s / c;
  return o;
}

}  // namespace

TEST(ObstacleContact, BallOscillatesAtTheSpringsFrequencyAndDamping) {
  const double m = 3.0, k = kRigid.stiffness, c = kRigid.damping;
  const double omega = std::sqrt(k / m), zeta = c / (2.0 * std::sqrt(k * m));
  const double period = 2 * kPi / (omega * std::sqrt(1 - zeta * zeta));
  const double decay = std::exp(-zeta * omega * period);  // 0.774 per period
  const double xs = m * 9.81 / k;                          // 1.47 mm
  // Symplectic Euler's period is short by (omega h)^2 / 24 (4 % at the default step, omega h =
  // 1.02); the implicit spring's row would be 32 % long and decay 0.05 per period.
  const Oscillation a = ball_oscillation(kDt), b = ball_oscillation(kDt / 4);
  EXPECT_NEAR(a.period / period, 1.0, 0.05);
  EXPECT_NEAR(b.period / period, 1.0, 0.01);
  EXPECT_NEAR(a.decay, decay, 0.03);
  EXPECT_NEAR(b.decay, decay, 0.01);
  EXPECT_NEAR(a.mean / xs, 1.0, 0.01);
  EXPECT_NEAR(b.mean / xs, 1.0, 0.01);
}

TEST(ObstacleContact, MergedPointIsDepthWeighted) {
  dContactGeom p[3]{};
  const double depth[3] = {1e-3, 3e-3, 0.0};
  for (int k = 0; k < 3; ++k) {
    p[k].pos[0] = k;  // x = 0, 1, 2
    p[k].normal[2] = 1.0;
    p[k].depth = depth[k];
  }
  p[1].normal[0] = 1.0;  // (1, 0, 1) at the deepest point
  dContactGeom m = detail::merge_contact_points(p, 3);
  EXPECT_DOUBLE_EQ(m.pos[0], 0.75);  // weights 1/4, 3/4, 0
  EXPECT_DOUBLE_EQ(m.depth, 3e-3);
  EXPECT_NEAR(m.normal[0], 0.75 / std::hypot(0.75, 1.0), 1e-15);
  EXPECT_NEAR(m.normal[2], 1.0 / std::hypot(0.75, 1.0), 1e-15);
  // no depth anywhere: the plain mean; normals cancelling: the deepest point's
  for (auto& q : p) q.depth = 0.0;
  EXPECT_DOUBLE_EQ(detail::merge_contact_points(p, 3).pos[0], 1.0);
  p[0].depth = 2e-3;
  p[0].normal[2] = 1.0;
  p[1].depth = 2e-3 - 1e-9;
  p[1].normal[0] = 0.0;
  p[1].normal[2] = -1.0;
  m = detail::merge_contact_points(p, 2);
  EXPECT_EQ(m.normal[2], 1.0);
}

TEST(ObstacleContact, LightBodiesFallBackToTheImplicitSpring) {
  using detail::spring_damper_row;
  const double k = kRigid.stiffness, c = kRigid.damping, h = kDt;
  const auto heavy = spring_damper_row(k, c, h, 3.0);  // omega h = 1.02
  EXPECT_TRUE(heavy.explicit_spring);
  EXPECT_DOUBLE_EQ(heavy.erp, h * k / c);
  EXPECT_DOUBLE_EQ(heavy.cfm, 1.0 / c);
  const auto light = spring_damper_row(k, c, h, 0.5);  // omega h = 2.5
  EXPECT_FALSE(light.explicit_spring);
  EXPECT_DOUBLE_EQ(light.erp, kRigid.erp(h));
  EXPECT_DOUBLE_EQ(light.cfm, kRigid.cfm(h));
  EXPECT_FALSE(spring_damper_row(k, c, h, std::nan("")).explicit_spring);
  EXPECT_FALSE(spring_damper_row(k, 0.0, h, 3.0).explicit_spring);  // no damper: no row
  // The bound is symplectic Euler's: a 0.5 kg ball's explicit spring grows without bound at the
  // default step, the fallback settles at m g / k.
  for (const bool force : {true, false}) {
    Bench b(0.5, 0.17, false, 9.81);
    b.force_explicit = force;
    dBodySetPosition(b.body, 0.0, 0.0, 0.17 - 2e-3);
    double worst = 0.0;
    for (int i = 0; i < 80; ++i) {
      b.step(h);
      worst = std::max(worst, std::abs(0.17 - b.z()));
    }
    if (force) {
      EXPECT_GT(worst, 0.05);
    } else {
      EXPECT_LT(worst, 2e-3 + 1e-9);
      EXPECT_NEAR(0.17 - b.z(), 0.5 * 9.81 / k, 1e-5);
    }
  }
}

TEST(ObstacleContact, WheelOnABoxTopIsPushedUnderItsCentre) {
  const double m = 3.0, r = RoverParameters{}.wheel_radius, g = 9.81;
  Bench b(m, r, true, g);
  dBodySetPosition(b.body, 0.1, 0.2, r - m * g / kRigid.stiffness);
  for (int i = 0; i < 240; ++i) b.step(kDt);  // 3 s
  EXPECT_GE(b.points, 2);  // ODE's points: a line contact's ends
  EXPECT_NEAR(b.merged.pos[0], 0.1, 1e-6);
  EXPECT_NEAR(b.merged.pos[1], 0.2, 1e-6);
  EXPECT_NEAR(b.merged.normal[2], 1.0, 1e-9);
  EXPECT_NEAR(b.fb.f1[2], m * g, 1e-3 * m * g);
  EXPECT_NEAR(std::hypot(b.fb.t1[0], b.fb.t1[1]), 0.0, 1e-6);  // about the centre: none
  const dReal* w = dBodyGetAngularVel(b.body);
  EXPECT_LT(std::abs(w[0]) + std::abs(w[1]) + std::abs(w[2]), 1e-9);
}

TEST(ObstacleContact, WheelPushingABoxFaceIsPushedAtItsAxleHeight) {
  // No gravity: a wheel at mid height of the box's x = 1 face pushed into it with 50 N.
  const double m = 3.0, r = RoverParameters{}.wheel_radius, f = 50.0;
  Bench b(m, r, true, 0.0);
  dBodySetPosition(b.body, 1.0 + r - f / kRigid.stiffness, 0.3, -1.0);
  for (int i = 0; i < 240; ++i) {
    dBodyAddForce(b.body, -f, 0.0, 0.0);
    b.step(kDt);
  }
  EXPECT_GE(b.points, 2);
  EXPECT_NEAR(b.merged.pos[1], 0.3, 1e-6);
  EXPECT_NEAR(b.merged.pos[2], -1.0, 1e-6);
  EXPECT_NEAR(b.merged.normal[0], 1.0, 1e-9);
  EXPECT_NEAR(b.fb.f1[0], f, 1e-3 * f);
  EXPECT_NEAR(std::hypot(b.fb.t1[1], b.fb.t1[2]), 0.0, 1e-6);
  const dReal* w = dBodyGetAngularVel(b.body);
  EXPECT_LT(std::abs(w[0]) + std::abs(w[1]) + std::abs(w[2]), 1e-9);
}

// The broad phase's early-out (cylinder_box_disjoint) only skips pairs that ODE's collider finds
// apart: over random poses of a wheel-sized cylinder and a rock-sized box, ODE finds no point
// wherever it says disjoint; and it is not vacuous: it proves most of ODE's misses.
TEST(ObstacleContact, CylinderBoxEarlyOutOnlySkipsPairsOdeFindsApart) {
  ernest::solver::init_ode_once();
  const double r = RoverParameters{}.wheel_radius, hl = 0.5 * RoverParameters{}.wheel_width;
  dSpaceID space = dSimpleSpaceCreate(nullptr);
  dGeomID cyl = dCreateCylinder(space, r, 2.0 * hl), box = dCreateBox(space, 1, 1, 1);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> uni(-1.0, 1.0), size(0.04, 0.4);
  const auto rotation = [&] {
    return Eigen::Quaterniond(Eigen::Vector4d(uni(rng), uni(rng), uni(rng), uni(rng)).normalized())
        .toRotationMatrix();
  };
  const auto set = [](dGeomID g, const Eigen::Vector3d& x, const Eigen::Matrix3d& m) {
    dMatrix3 o;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j) o[4 * i + j] = j < 3 ? m(i, j) : 0.0;
    dGeomSetPosition(g, x.x(), x.y(), x.z());
    dGeomSetRotation(g, o);
  };
  int wrong = 0, misses = 0, proved = 0, hits = 0;
  for (int k = 0; k < 20000; ++k) {
    const Eigen::Vector3d e(size(rng), size(rng), size(rng)), c(0.5 * uni(rng), 0.5 * uni(rng),
                                                                   0.5 * uni(rng));
    const Eigen::Matrix3d rb = rotation(), rc = rotation();
    dGeomBoxSetLengths(box, 2 * e.x(), 2 * e.y(), 2 * e.z());
    set(box, Eigen::Vector3d::Zero(), rb);
    set(cyl, c, rc);
    dContactGeom pts[4];
    const int n = dCollide(cyl, box, 4, pts, sizeof(dContactGeom));
    const bool disjoint =
        detail::cylinder_box_disjoint(c, rc.col(2), r, hl, Eigen::Vector3d::Zero(), rb, e);
    if (disjoint && n > 0) ++wrong;
    if (n > 0) ++hits;
    if (n == 0) ++misses, proved += disjoint;
  }
  dSpaceDestroy(space);
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(hits, 2000);  // both kinds of pose are well sampled
  EXPECT_GT(misses, 2000);
  EXPECT_GT(proved, 0.9 * misses);
}

// Closed forms: a wheel (axle along y) over a box top with its rim 1 mm clear of it is disjoint,
// 1 mm into it is not; beside the box's x face likewise; off the box's edge diagonally, clear of
// it though inside the bounding sphere, disjoint by the nearest-point axis.
TEST(ObstacleContact, CylinderBoxEarlyOutClosedForms) {
  const double r = 0.17, hl = 0.065;
  const Eigen::Vector3d e(0.2, 0.2, 0.1), y = Eigen::Vector3d::UnitY(), o = Eigen::Vector3d::Zero();
  const Eigen::Matrix3d id = Eigen::Matrix3d::Identity();
  for (const double gap : {1e-3, -1e-3}) {
    EXPECT_EQ(detail::cylinder_box_disjoint({0, 0, 0.1 + r + gap}, y, r, hl, o, id, e), gap > 0);
    EXPECT_EQ(detail::cylinder_box_disjoint({0.2 + r + gap, 0, 0}, y, r, hl, o, id, e), gap > 0);
  }
  // the box's top edge at x = 0.2, z = 0.1; the wheel centre 45 deg off it at r + 1 mm
  const double d = (r + 1e-3) / std::sqrt(2.0);
  EXPECT_TRUE(detail::cylinder_box_disjoint({0.2 + d, 0, 0.1 + d}, y, r, hl, o, id, e));
  EXPECT_FALSE(detail::cylinder_box_disjoint({0.2 + d - 2e-3, 0, 0.1 + d - 2e-3}, y, r, hl, o, id, e));
}
