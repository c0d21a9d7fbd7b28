// A wheel against a rock (benchmarks/RESULTS.md, "Measured and not kept"): ODE's dCollideCylinderBox merged into one contact (what near() in
// cpp/dynamics/obstacle_contacts.cpp does with SimOptions::wheel_obstacle_contact = Ode), the
// exact contact (cylinder_box.hpp, Exact), and FCL's cylinder-box (libccd's GJK/EPA and FCL's own
// GJK solver) on the same 1000 touching poses: a wheel-sized cylinder (axle within 6 deg of
// horizontal, yawed within 11 deg) near a yawed rock-sized box, kept where ODE finds a contact.
// Prints the wall clock per call of ODE and Exact (medians of 31 alternated runs) and the ratio.
// Each collider runs in its own non-inlined function so that callgrind gives its cost:
//   valgrind --tool=callgrind --callgrind-out-file=/tmp/cb.out build/bench/benchmarks/profile_cylinder_box
//   callgrind_annotate --inclusive=yes /tmp/cb.out | grep -E 'ode_calls|fcl_calls'
#include <ode/ode.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fcl/fcl.h>
#include <random>
#include <vector>

#include "ernest/dynamics/cylinder_box.hpp"
#include "ernest/dynamics/obstacle_contacts.hpp"
#include "ernest/dynamics/rover_parameters.hpp"
#include "ernest/solver/ode_init.hpp"

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

__attribute__((noinline)) double ode_calls(const std::vector<Pose>& poses, dGeomID cyl,
                                            dGeomID box) {
  double sum = 0.0;
  for (const Pose& p : poses) {
    dContactGeom pts[4];
    dGeomBoxSetLengths(box, 2 * p.half.x(), 2 * p.half.y(), 2 * p.half.z());
    set(box, Eigen::Vector3d::Zero(), p.rock_rot);
    set(cyl, p.wheel_centre, p.wheel_rot);
    const int n = dCollide(cyl, box, 4, pts, sizeof(dContactGeom));
    if (n > 0) sum += ernest::dynamics::detail::merge_contact_points(pts, n).depth;
  }
  return sum;
}

__attribute__((noinline)) double exact_calls(const std::vector<Pose>& poses, double r, double hl) {
  double sum = 0.0;
  for (const Pose& p : poses) {
    ernest::dynamics::detail::CylinderBoxContact c;
    if (ernest::dynamics::detail::cylinder_box_contact(p.wheel_centre, p.wheel_rot.col(2), r, hl,
                                                       Eigen::Vector3d::Zero(), p.rock_rot,
                                                       p.half, c))
      sum += c.depth;
  }
  return sum;
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
  ernest::solver::init_ode_once();
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
  // The same poses moved apart along the exact normal to a depth in [0, 1 cm] (the rover's
  // regime: mm), kept where ODE finds a contact too.
  std::vector<Pose> shallow;
  for (const Pose& p : poses) {
    ernest::dynamics::detail::CylinderBoxContact c;
    Pose s = p;
    if (!ernest::dynamics::detail::cylinder_box_contact(p.wheel_centre, p.wheel_rot.col(2), r,
                                                        0.5 * w, Eigen::Vector3d::Zero(),
                                                        p.rock_rot, p.half, c))
      continue;
    s.wheel_centre += (c.depth - 0.005 * (1.0 + uni(rng))) * c.normal;
    if (ode_points(s, cyl, box) > 0) shallow.push_back(s);
  }
  int ode = 0;
  for (const Pose& p : poses) ode += ode_points(p, cyl, box);
  const int ccd = fcl_calls(poses, r, w, fcl::GST_LIBCCD);
  const int indep = fcl_calls(poses, r, w, fcl::GST_INDEP);
  std::printf("%zu touching poses: ODE %d points, FCL libccd %d contacts, FCL indep %d contacts\n",
              poses.size(), ode, ccd, indep);
  // wall clock, alternated runs, medians [ns per call]
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  for (const auto* set_of : {&poses, &shallow}) {
    std::vector<double> t_ode, t_exact;
    double sink = 0.0;
    using clock = std::chrono::steady_clock;
    for (int rep = 0; rep < 31; ++rep) {
      auto t0 = clock::now();
      sink += ode_calls(*set_of, cyl, box);
      auto t1 = clock::now();
      sink += exact_calls(*set_of, r, 0.5 * w);
      auto t2 = clock::now();
      const double count = static_cast<double>(set_of->size());
      t_ode.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / count);
      t_exact.push_back(std::chrono::duration<double, std::nano>(t2 - t1).count() / count);
    }
    const double mo = median(t_ode), me = median(t_exact);
    std::printf("%4zu %s poses, per call (median of 31): ODE + merge %.0f ns, Exact %.0f ns, "
                "Exact / ODE %.2f (sum of depths %.3g)\n", set_of->size(),
                set_of == &poses ? "touching" : "shallow ", mo, me, me / mo, sink);
  }
  dSpaceDestroy(space);
  return 0;
}
