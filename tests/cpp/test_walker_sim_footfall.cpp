// One rock field for planner and simulator (boxes rasterised into the planner's height map) and a
// full FootFall gait cycle around rocks (seed 003 §6, Fig. 19) planned and executed in the ODE
// walker: every wheel keeps clear of every rock and the body advances by the planned amount.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "ernest/walker_sim/footfall_cycle.hpp"
#include "ernest/walker_sim/rock_map.hpp"
#include "test_util.hpp"

using namespace ernest::walker_sim;
using ernest::testing::invalid_argument_message;
using ernest::walker::WalkerModel;

namespace {
const WalkerModel& sdm_b() {
  static const WalkerModel m(ernest::walker::sdm_b_parameters());
  return m;
}

// The demo's world (python/ernest_cpp/footfall_cycle.py rock_world): 60 boxes, none within 0.45 m
// of the feet; the nominal footholds a stride ahead may be taken (the planner moves them).
struct World {
  std::vector<Rock> rocks;
  ernest::dynamics::HeightMap terrain = ernest::dynamics::HeightMap::flat(1.0, 1.0, 0.5);
};
World demo_world() {
  const WalkerModel& m = sdm_b();
  const Eigen::Matrix2Xd keep = m.contact_points(m.standard_body_pose(), m.standard_configuration()).topRows<2>();
  ernest::footfall::RockFieldOptions ro;
  ro.rocks = 60, ro.seed = 3, ro.length = 8.0, ro.centre_x = 0.5, ro.keep_clear = 0.45, ro.inner_radius = 1.4;
  ro.min_height = 0.1, ro.max_height = 0.45, ro.min_radius = 0.1, ro.max_radius = 0.3;
  World w;
  w.rocks = box_rock_field(ro, keep);
  RockMapOptions mo;
  mo.length = ro.length, mo.centre_x = ro.centre_x, mo.spacing = 0.02, mo.dilation = std::sqrt(2.0) * 0.02;
  w.terrain = rock_height_map(w.rocks, mo);
  return w;
}
}  // namespace

TEST(RockMap, NodeHeightIsTheBoxTopInsideItsFootprintAndZeroOutside) {
  Rock a, b;
  a.centre = {0.3, -0.2, 0.1}, a.half_extents = {0.25, 0.1, 0.1}, a.yaw = 0.6;  // top 0.2
  b.centre = {-0.5, 0.4, 0.05}, b.half_extents = {0.12, 0.3, 0.2}, b.yaw = -1.1;  // top 0.25, half buried
  RockMapOptions o;
  o.length = 2.0, o.spacing = 0.013;
  const ernest::dynamics::HeightMap map = rock_height_map({a, b}, o);
  const Eigen::MatrixXd& h = map.heights();
  int inside = 0, outside = 0;
  for (Eigen::Index i = 0; i < h.rows(); ++i)
    for (Eigen::Index j = 0; j < h.cols(); ++j) {
      const Eigen::Vector3d p(map.origin_x() + i * o.spacing, map.origin_y() + j * o.spacing, 0.0);
      double expect = 0.0;
      bool on_edge = false;
      for (const Rock& r : {a, b}) {
        // independent of the rasteriser's arithmetic: the node in the box frame by Eigen's rotation
        const Eigen::Vector3d l = Eigen::AngleAxisd(-r.yaw, Eigen::Vector3d::UnitZ()) * (p - r.centre);
        const double gap = std::max(std::abs(l.x()) - r.half_extents.x(), std::abs(l.y()) - r.half_extents.y());
        on_edge = on_edge || std::abs(gap) < 1e-9;  // on an edge: either answer is right
        if (gap < 0.0) expect = std::max(expect, r.centre.z() + r.half_extents.z());
      }
      if (on_edge) continue;
      EXPECT_EQ(h(i, j), expect) << i << ", " << j;
      (expect > 0.0 ? inside : outside)++;
    }
  // the footprint areas (2 hx 2 hy) in nodes, to the raster's resolution
  EXPECT_NEAR(inside * o.spacing * o.spacing, 4 * (0.25 * 0.1 + 0.12 * 0.3), 0.02);
  EXPECT_GT(outside, 10 * inside);
  // Dilated by a cell's diagonal, the bilinear map never lies below a box anywhere over its
  // footprint (by one step only, it does near the corners of a yawed box).
  o.dilation = std::sqrt(2.0) * o.spacing;
  const ernest::dynamics::HeightMap cover = rock_height_map({a}, o);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int s = 0; s < 2000; ++s) {
    const Eigen::Vector3d p = a.centre + Eigen::AngleAxisd(a.yaw, Eigen::Vector3d::UnitZ()) *
                                             Eigen::Vector3d(u(rng) * a.half_extents.x(), u(rng) * a.half_extents.y(), 0);
    EXPECT_GE(cover.height(p.x(), p.y()), 0.2 - 1e-12);
  }
  o.spacing = 0.0;
  EXPECT_NE(invalid_argument_message([&] { rock_height_map({a}, o); }).find("spacing"), std::string::npos);
}

TEST(RockMap, BoxFieldIsSeededAndKeepsClearOfThePoints) {
  ernest::footfall::RockFieldOptions ro;
  ro.rocks = 30, ro.length = 6.0, ro.inner_radius = 1.0;
  const Eigen::Matrix2Xd keep = (Eigen::Matrix2Xd(2, 2) << 2.0, -2.0, 0.0, 1.0).finished();
  const std::vector<Rock> r1 = box_rock_field(ro, keep), r2 = box_rock_field(ro, keep);
  ASSERT_EQ(r1.size(), 30u);
  for (std::size_t k = 0; k < r1.size(); ++k) {
    EXPECT_EQ(r1[k].centre, r2[k].centre);
    EXPECT_DOUBLE_EQ(r1[k].centre.z(), r1[k].half_extents.z());  // standing on z = 0
    const double circum = r1[k].half_extents.head<2>().norm();
    EXPECT_GE(r1[k].centre.head<2>().norm(), ro.inner_radius + circum);
    for (int c = 0; c < 2; ++c) EXPECT_GE((r1[k].centre.head<2>() - keep.col(c)).norm(), ro.keep_clear + circum);
  }
}

TEST(FootfallCycle, ExecutedCycleClearsEveryRockAndAdvancesTheBodyAsPlanned) {
  const WalkerModel& m = sdm_b();
  FootfallCycleOptions o;
  o.step.map.cell = 0.05;  // coarse maps keep the test fast; the demo uses 2 cm
  o.step.planner.seed = 3;
  const World w = demo_world();
  const FootfallCycleResult r = run_footfall_cycle(m, w.terrain, w.rocks, o);
  ASSERT_TRUE(r.completed) << r.reason;
  ASSERT_EQ(r.steps.size(), 6u);
  int moved = 0;
  for (const FootfallStepRecord& s : r.steps) {
    EXPECT_GT(s.min_rock_clearance, 0.0) << "leg " << s.leg;
    EXPECT_GT(s.transfer_ground_clearance, 0.0) << "leg " << s.leg;  // the wheel left the ground
    EXPECT_LE(s.plan.smoothing.length, s.plan.plan.length + 1e-9);
    // the foothold is rock-free: the planner's map is flat ground within the wheel's footprint
    EXPECT_EQ(w.terrain.height(s.plan.goal.x(), s.plan.goal.y()), 0.0);
    moved += (s.plan.goal.head<2>() - s.nominal_goal).norm() > o.step.map.cell;
    std::printf("leg %d: clearance planned %.3f executed swing %.3f all %.3f m, transfer %.3f m\n", s.leg,
                s.planned_clearance, s.swing_rock_clearance, s.min_rock_clearance, s.transfer_ground_clearance);
  }
  EXPECT_GE(moved, 1);  // at least one nominal foothold was on or near a rock
  EXPECT_GT(r.min_rock_clearance, 0.0);
  EXPECT_NEAR(r.planned_advance, o.stride, 1e-12);
  // Open loop, the body ends where the joint targets put it over the feet, which stick (Coulomb
  // friction): its error is the joints' tracking error (the P law leaves ~1e-3 rad under load)
  // times the ~2 m legs, a few mm; 1 cm bounds it (a slipping foot would show as more).
  const Eigen::Vector3d moved_body = r.body_end - r.body_start;
  std::printf("advance %.4f m (planned %.4f), lateral %.4f m, min clearance %.3f m\n", moved_body.x(),
              r.planned_advance, moved_body.y(), r.min_rock_clearance);
  EXPECT_NEAR(moved_body.x(), r.planned_advance, 0.01);
  EXPECT_NEAR(moved_body.y(), 0.0, 0.01);
}

TEST(FootfallCycle, WithoutSagCompensationTheSwingWheelComesCloserToTheTerrain) {
  // §4.1: a plan made on the rigid pose lifts the wheel by lift_height on paper, but the chassis
  // sags when the leg unloads and takes the wheel down by about the swing hip's predicted sag.
  const WalkerModel& m = sdm_b();
  FootfallCycleOptions o;
  o.step.map.cell = 0.05;
  o.step.planner.seed = 3;
  o.steps = 2;
  const World w = demo_world();
  const FootfallCycleResult comp = run_footfall_cycle(m, w.terrain, w.rocks, o);
  o.step.sag_compensation = false;
  const FootfallCycleResult rigid = run_footfall_cycle(m, w.terrain, w.rocks, o);
  ASSERT_TRUE(comp.completed && rigid.completed) << comp.reason << rigid.reason;
  for (int k = 0; k < 2; ++k) {
    const FootfallStepRecord &a = comp.steps[k], &b = rigid.steps[k];
    const double sag = -a.plan.sag.hip_displacement.z();
    std::printf("leg %d: transfer clearance compensated %.3f, rigid %.3f m (predicted hip sag %.3f); rock "
                "clearance %.3f vs %.3f m\n", a.leg, a.transfer_ground_clearance, b.transfer_ground_clearance, sag,
                a.swing_rock_clearance, b.swing_rock_clearance);
    EXPECT_GT(sag, 0.01);
    EXPECT_LT(b.transfer_ground_clearance, a.transfer_ground_clearance - 0.5 * sag) << "leg " << a.leg;
    EXPECT_GT(b.min_rock_clearance, 0.0);
  }
}

TEST(FootfallCycle, BadOptionsNameTheField) {
  const WalkerModel& m = sdm_b();
  const ernest::dynamics::HeightMap flat = ernest::dynamics::HeightMap::flat(8.0, 8.0, 0.05, 0.0, -4.0, -4.0);
  FootfallCycleOptions o;
  o.stride = std::nan("");
  EXPECT_NE(invalid_argument_message([&] { run_footfall_cycle(m, flat, {}, o); }).find("stride"), std::string::npos);
  o = FootfallCycleOptions{};
  o.steps = 7;  // more than the six legs
  EXPECT_NE(invalid_argument_message([&] { run_footfall_cycle(m, flat, {}, o); }).find("steps"), std::string::npos);
  o.steps = 0;  // no 0 for "every leg": that is the unset field
  EXPECT_NE(invalid_argument_message([&] { run_footfall_cycle(m, flat, {}, o); }).find("steps = 0"),
            std::string::npos);
  o = FootfallCycleOptions{};
  o.execution.frame_interval = -1.0;
  EXPECT_NE(invalid_argument_message([&] { run_footfall_cycle(m, flat, {}, o); }).find("frame_interval"),
            std::string::npos);
}
