// Driver for instruction counts of a wheel against a rock (issue 17 item 1, "Session 10:
// collision" in RESULTS.md): ODE's dCollideCylinderBox, which the obstacle contacts use
// (cpp/dynamics/obstacle_contacts.cpp), against FCL's cylinder-box (libccd's GJK/EPA and FCL's own
// GJK solver) on the same 1000 touching poses: a wheel-sized cylinder (axle within 6 deg of
// horizontal, yawed within 11 deg) near a yawed rock-sized box, kept where ODE finds a contact.
// Each collider runs in its own non-inlined function so that callgrind gives its cost:
//   valgrind --tool=callgrind --callgrind-out-file=/tmp/cb.out build/bench/benchmarks/profile_cylinder_box
//   callgrind_annotate --inclusive=yes /tmp/cb.out | grep -E 'ode_calls|fcl_calls'
#include <ode/ode.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <fcl/fcl.h>
#include <random>
#include <vector>

#include "ernest/dynamics/ode_init.hpp"
#include "ernest/dynamics/rover_parameters.hpp"

namespace {

struct Pose {
  Eigen::Matrix3d rock_rot, wheel_rot;
  Eigen::Vector3d half, wheel_centre;  // the rock's centre is the origin
};

void set(dGeomID g, const Eigen::Vector3d& x, const Eigen::Matrix3d& m) {
  dMatrix3 o;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) o[4 * i + j] = j < 3 ? m(i, j) : 0.0;
  dGeomSetPosition(g, x.x(), x.y(), x.z());
  dGeomSetRotation(g, o);
}

int ode_points(const Pose& p, dGeomID cyl, dGeomID box) {
  dContactGeom pts[4];
  dGeomBoxSetLengths(box, 2 * p.half.x(), 2 * p.half.y(), 2 * p.half.z());
  set(box, Eigen::Vector3d::Zero(), p.rock_rot);
  set(cyl, p.wheel_centre, p.wheel_rot);
  return dCollide(cyl, box, 4, pts, sizeof(dContactGeom));
}

__attribute__((noinline)) int ode_calls(const std::vector<Pose>& poses, dGeomID cyl, dGeomID box) {
  int points = 0;
  for (const Pose& p : poses) points += ode_points(p, cyl, box);
  return points;
}

__attribute__((noinline)) int fcl_calls(const std::vector<Pose>& poses, double r, double w,
                                        fcl::GJKSolverType solver) {
  int contacts = 0;
  auto cyl = std::make_shared<fcl::Cylinderd>(r, w);
  for (const Pose& p : poses) {
    auto box = std::make_shared<fcl::Boxd>(2 * p.half);
    fcl::Transform3d tb = fcl::Transform3d::Identity(), tc = fcl::Transform3d::Identity();
    tb.linear() = p.rock_rot;
    tc.linear() = p.wheel_rot;
    tc.translation() = p.wheel_centre;
    const fcl::CollisionObjectd a(cyl, tc), b(box, tb);
    fcl::CollisionRequestd req(1, true);  // one contact with its depth and normal
    req.gjk_solver_type = solver;
    fcl::CollisionResultd res;
    contacts += static_cast<int>(fcl::collide(&a, &b, req, res));
  }
  return contacts;
}

}  // namespace

int main() {
  ernest::dynamics::detail::init_ode_once();
  const ernest::dynamics::RoverParameters rp;
  const double r = rp.wheel_radius, w = rp.wheel_width;
  dSpaceID space = dSimpleSpaceCreate(nullptr);
  dGeomID cyl = dCreateCylinder(space, r, w), box = dCreateBox(space, 1, 1, 1);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> uni(-1.0, 1.0), size(0.04, 0.2);
  std::vector<Pose> poses;
  while (poses.size() < 1000) {
    Pose p;
    p.half = {size(rng), size(rng), size(rng)};
    p.rock_rot = Eigen::AngleAxisd(3.14 * uni(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    p.wheel_rot = (Eigen::AngleAxisd(0.2 * uni(rng), Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(1.5708 + 0.1 * uni(rng), Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();  // the cylinder's axis (local z) near world y
    p.wheel_centre = {0.4 * uni(rng), 0.4 * uni(rng), 0.3 * uni(rng)};
    if (ode_points(p, cyl, box) > 0) poses.push_back(p);
  }
  const int ode = ode_calls(poses, cyl, box);
  const int ccd = fcl_calls(poses, r, w, fcl::GST_LIBCCD);
  const int indep = fcl_calls(poses, r, w, fcl::GST_INDEP);
  std::printf("%zu touching poses: ODE %d points, FCL libccd %d contacts, FCL indep %d contacts\n",
              poses.size(), ode, ccd, indep);
  dSpaceDestroy(space);
  return 0;
}
