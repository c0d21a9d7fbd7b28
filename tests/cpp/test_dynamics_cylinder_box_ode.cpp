// The exact wheel–rock contact (cpp/dynamics/cylinder_box.hpp) against ODE's collider merged into
// one contact (merge_contact_points, what near() does with WheelObstacleContact::Ode): the
// dContactGeom conventions, the option's validation, and thousands of random touching poses with
// the differences printed.
#include <gtest/gtest.h>
#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "cylinder_box_poses.hpp"
#include "ernest/dynamics/obstacle_contacts.hpp"
#include "ernest/solver/ode_init.hpp"
#include "ernest/dynamics/rover_sim.hpp"

using namespace ernest::dynamics;
using namespace cylinder_box_poses;

namespace {

// ODE's cylinder-box merged into one contact (what near() does with Ode) against ours over the
// rover's poses (axle near horizontal, yawed rocks; profile_cylinder_box's distribution) and
// over any orientation. ODE's normal is one of its candidate axes, whose overlap is never below
// our depth; the normals agree where ODE's axis is the exact one (all but its approximate
// rim-edge axes and ties), and the points differ by ODE's choices (its cap as an 8-gon, the
// generator regime by the same 0.9 threshold). The distributions are printed.
void compare_with_ode(bool any_axis, int count) {
  constexpr double kShallow = 0.02;  // [m]
  ernest::solver::init_ode_once();
  dGeomID cyl = dCreateCylinder(nullptr, kR, 2 * kHl), box = dCreateBox(nullptr, 1, 1, 1);
  const auto set = [](dGeomID g, const Vec3& x, const Mat3& m) {
    dMatrix3 o;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j) o[4 * i + j] = j < 3 ? m(i, j) : 0.0;
    dGeomSetPosition(g, x.x(), x.y(), x.z());
    dGeomSetRotation(g, o);
  };
  std::mt19937 rng(any_axis ? 3 : 5);
  std::vector<double> angle, ddepth, dpos;
  int ours_only = 0, ode_only = 0, above = 0, differ_by_axis[5] = {};
  while (static_cast<int>(angle.size()) < count) {
    const Pose p = random_pose(rng, any_axis);
    dGeomBoxSetLengths(box, 2 * p.e.x(), 2 * p.e.y(), 2 * p.e.z());
    set(box, p.b, p.rb);
    const Mat3 rc = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), p.u).toRotationMatrix();
    set(cyl, p.c, rc);
    dContactGeom pts[8];
    const int n = dCollide(cyl, box, 8, pts, sizeof(dContactGeom));
    CylinderBoxContact k;
    const bool hit = contact(p.c, p.u, p.b, p.rb, p.e, k);
    if (hit && k.depth > kShallow) continue;  // the rover's regime: mm, not a wheel inside a rock
    if (n <= 0 || !hit) {
      ours_only += hit && n <= 0;
      ode_only += !hit && n > 0;
      continue;
    }
    const dContactGeom m = detail::merge_contact_points(pts, n);
    EXPECT_EQ(m.g1, cyl);
    EXPECT_EQ(m.g2, box);
    const Vec3 on(m.normal[0], m.normal[1], m.normal[2]), op(m.pos[0], m.pos[1], m.pos[2]);
    // ODE's axis: an upper bound of the depth (up to ODE's rounding in its normalisation)
    EXPECT_GE(overlap(p, on), k.depth - 1e-9);
    above += overlap(p, on) > k.depth + 1e-9;
    if (overlap(p, on) > k.depth + 1e-9) ++differ_by_axis[k.axis];
    angle.push_back(std::acos(std::clamp(on.dot(k.normal), -1.0, 1.0)));
    ddepth.push_back(m.depth - k.depth);
    dpos.push_back((op - k.pos).norm());
  }
  const auto q = [](std::vector<double> v, double f) {
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(f * (v.size() - 1))];
  };
  std::printf("%s, %d poses touching by < 2 cm (ours only %d, ODE only %d; ODE's axis deeper %d):\n",
              any_axis ? "any orientation" : "rover poses", count, ours_only, ode_only, above);
  std::printf("  normal angle [rad] median %.2e p90 %.2e p99 %.2e max %.2e\n", q(angle, 0.5),
              q(angle, 0.9), q(angle, 0.99), q(angle, 1.0));
  std::printf("  depth ODE - ours [m] p1 %.2e median %.2e p99 %.2e\n", q(ddepth, 0.01),
              q(ddepth, 0.5), q(ddepth, 0.99));
  std::printf("  point distance [m] median %.2e p90 %.2e p99 %.2e max %.2e\n", q(dpos, 0.5),
              q(dpos, 0.9), q(dpos, 0.99), q(dpos, 1.0));
  std::printf("  where ODE's axis is deeper, ours is: face %d cap %d cross %d vertex %d rim-edge %d\n",
              differ_by_axis[0], differ_by_axis[1], differ_by_axis[2], differ_by_axis[3],
              differ_by_axis[4]);
  EXPECT_LT(q(angle, 0.5), 1e-6);  // the same axis (up to ODE's rounding) in most poses
  dGeomDestroy(cyl);
  dGeomDestroy(box);
}

// The exact contact as the dContactGeom near() records: the geom order, normal and sides of
// merge_contact_points(dCollide(cylinder, box)).
TEST(CylinderBox, ContactGeomHasOdesConventions) {
  ernest::solver::init_ode_once();
  dGeomID cyl = dCreateCylinder(nullptr, kR, 2 * kHl), box = dCreateBox(nullptr, 0.6, 0.6, 0.2);
  const Mat3 rc = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), kY).toRotationMatrix();
  dMatrix3 o;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) o[4 * i + j] = j < 3 ? rc(i, j) : 0.0;
  const Vec3 c(0.05, 0.0, 0.1 + kR - 0.01);
  dGeomSetPosition(cyl, c.x(), c.y(), c.z());
  dGeomSetRotation(cyl, o);
  dContactGeom pts[8];
  const int n = dCollide(cyl, box, 8, pts, sizeof(dContactGeom));
  ASSERT_GT(n, 0);
  const dContactGeom ode = detail::merge_contact_points(pts, n);
  CylinderBoxContact k;
  ASSERT_TRUE(contact(c, kY, Vec3::Zero(), Mat3::Identity(), Vec3(0.3, 0.3, 0.1), k));
  const dContactGeom ours = detail::to_contact_geom(k, cyl, box);
  EXPECT_EQ(ours.g1, ode.g1);
  EXPECT_EQ(ours.g2, ode.g2);
  EXPECT_EQ(ours.side1, ode.side1);
  EXPECT_EQ(ours.side2, ode.side2);
  EXPECT_NEAR(ours.depth, ode.depth, 1e-12);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(ours.normal[i], ode.normal[i], 1e-12);
    EXPECT_NEAR(ours.pos[i], ode.pos[i], 1e-12);
  }
  dGeomDestroy(cyl);
  dGeomDestroy(box);
}

TEST(CylinderBox, OptionIsValidated) {
  SimOptions o;
  EXPECT_EQ(o.wheel_obstacle_contact, WheelObstacleContact::Ode);
  o.wheel_obstacle_contact = WheelObstacleContact::Exact;
  o.validate();
  o.wheel_obstacle_contact = static_cast<WheelObstacleContact>(7);
  try {
    o.validate();
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("wheel_obstacle_contact = 7"), std::string::npos);
  }
}

TEST(CylinderBox, AgainstOdeRoverPoses) { compare_with_ode(false, 3000); }
TEST(CylinderBox, AgainstOdeAnyOrientation) { compare_with_ode(true, 3000); }

}  // namespace
