// The planner's DEM from a perception elevation map (footfall/terrain_map): a box seen with holes
// round-trips to closed-form heights (raised by k sigma), small holes are filled from above and
// large ones become obstacle columns the stability map cannot stand on; NaN and empty maps give
// clear errors; and NaN poses throw, planning ends within its budget.
#include <gtest/gtest.h>

#include <cmath>

#include "ernest/footfall/leg_planner.hpp"
#include "ernest/footfall/scenario.hpp"
#include "ernest/footfall/stability_map.hpp"
#include "ernest/footfall/step_planner.hpp"
#include "ernest/footfall/terrain_map.hpp"
#include "ernest/perception/elevation_map.hpp"
#include "ernest/walker/stance_loads.hpp"
#include "test_util.hpp"

using namespace ernest::footfall;
using ernest::dynamics::HeightMap;
using ernest::testing::invalid_argument_message;
namespace walker = ernest::walker;

namespace {

constexpr double kRes = 0.01, kSigma = 0.01, kBox = 0.3;
constexpr std::uint8_t kUnknown = static_cast<std::uint8_t>(TerrainCell::kUnknown);

// 2 m x 2 m at 1 cm from (-1, -1): ground 0 and a 0.3 m box on [0.2, 0.6] x [-0.2, 0.2], every
// 7th cell a hole, and a 0.3 m square hole (an occlusion shadow) on [-0.8, -0.5] x [0.4, 0.7].
struct SeenBox {
  Eigen::MatrixXd h, v;
  static bool in_box(double x, double y) { return x >= 0.2 && x <= 0.6 && y >= -0.2 && y <= 0.2; }
  static bool in_shadow(double x, double y) { return x >= -0.8 && x <= -0.5 && y >= 0.4 && y <= 0.7; }
  SeenBox() : h(201, 201), v(201, 201) {
    for (int i = 0; i < 201; ++i)
      for (int j = 0; j < 201; ++j) {
        const double x = -1 + i * kRes, y = -1 + j * kRes;
        const bool hole = (i * 201 + j) % 7 == 0 || in_shadow(x, y);
        h(i, j) = hole ? std::nan("") : in_box(x, y) ? kBox : 0.0;
        v(i, j) = hole ? INFINITY : kSigma * kSigma;
      }
  }
};

}  // namespace

TEST(FootfallTerrain, SeenBoxWithHolesRoundTrips) {
  const SeenBox b;
  MapTerrainOptions o;  // 5 cm spacing, k = 2, holes within 5 cm filled
  const MapTerrain t = terrain_from_map(b.h, b.v, kRes, -1.0, -1.0, o);
  ASSERT_EQ(t.terrain.heights().rows(), 41);
  ASSERT_EQ(t.terrain.heights().cols(), 41);
  EXPECT_NEAR(t.top, kBox + 2 * kSigma, 1e-12);
  int checked_box = 0, checked_ground = 0;
  for (int I = 0; I < 41; ++I)
    for (int J = 0; J < 41; ++J) {
      const double x = -1 + 0.05 * I, y = -1 + 0.05 * J, z = t.terrain.heights()(I, J);
      // Closed form away from edges (one spacing + half a cell): the raised surface or the column.
      // (plus the fill radius for the ground: a filled hole takes its highest neighbour)
      const double d = 0.05 + 0.5 * kRes + 1e-9, dg = d + o.fill_radius;
      bool near_shadow = false, near_box = false, inside_box = true;
      for (double dx : {-1.0, 1.0})
        for (double dy : {-1.0, 1.0}) {
          near_shadow |= SeenBox::in_shadow(x + dg * dx, y + dg * dy);
          near_box |= SeenBox::in_box(x + dg * dx, y + dg * dy);
          inside_box &= SeenBox::in_box(x + d * dx, y + d * dy);
        }
      near_shadow |= SeenBox::in_shadow(x, y);
      if (SeenBox::in_shadow(x, y)) {
        EXPECT_EQ(t.state(I, J), kUnknown) << x << ", " << y;
        EXPECT_NEAR(z, t.top + o.unknown_height, 1e-12);
        EXPECT_TRUE(t.unknown_at(x, y));
      } else if (!near_shadow && inside_box) {
        EXPECT_NEAR(z, kBox + 2 * kSigma, 1e-12);
        ++checked_box;
      } else if (!near_shadow && !near_box) {
        EXPECT_NEAR(z, 2 * kSigma, 1e-12);
        ++checked_ground;
        EXPECT_EQ(t.state(I, J), static_cast<std::uint8_t>(TerrainCell::kFilled));  // a 1-in-7 hole nearby
      }
    }
  EXPECT_GT(checked_box, 10);
  EXPECT_GT(checked_ground, 500);
  EXPECT_EQ(t.observed + t.filled + t.unknown, 41 * 41);
  EXPECT_GT(t.filled_cells, 5000);
  // Upper envelope: at every seen cell centre the planner's bilinear surface is at or above it.
  for (int i = 0; i < 201; ++i)
    for (int j = 0; j < 201; ++j)
      if (std::isfinite(b.h(i, j)))
        ASSERT_GE(t.terrain.height(-1 + i * kRes, -1 + j * kRes), b.h(i, j) + 2 * kSigma - 1e-12) << i << ", " << j;
}

TEST(FootfallTerrain, NanEmptyAndUncertainMaps) {
  const SeenBox b;
  // NaN variance with a finite height, or sigma above max_sigma: unseen, not ground (20 x 20 cell
  // blocks: their cores lie beyond the fill radius).
  Eigen::MatrixXd v = b.v;
  v.block(150, 150, 20, 20).setConstant(std::nan(""));
  v.block(20, 20, 20, 20).setConstant(0.5 * 0.5);
  const MapTerrain t = terrain_from_map(b.h, v, kRes, -1.0, -1.0);
  EXPECT_TRUE(t.unknown_at(-1 + 1.6, -1 + 1.6));
  EXPECT_TRUE(t.unknown_at(-1 + 0.3, -1 + 0.3));
  EXPECT_FALSE(t.unknown_at(-1 + 1.0, -1 + 1.0));
  EXPECT_TRUE(t.unknown_at(5.0, 0.0));  // outside the map
  EXPECT_TRUE(t.unknown_at(std::nan(""), 0.0));
  // Without filling, the 1-in-7 holes leave no fully seen vertex: an explicit error, no map.
  MapTerrainOptions no_fill;
  no_fill.fill_radius = 0.0;
  EXPECT_NE(invalid_argument_message([&] { terrain_from_map(b.h, b.v, kRes, -1.0, -1.0, no_fill); })
                .find("no planner cell"),
            std::string::npos);
  const Eigen::MatrixXd all_nan = Eigen::MatrixXd::Constant(50, 50, std::nan(""));
  const Eigen::MatrixXd inf = Eigen::MatrixXd::Constant(50, 50, INFINITY);
  EXPECT_NE(invalid_argument_message([&] { terrain_from_map(all_nan, inf, kRes, 0, 0); }).find("no observed cell"),
            std::string::npos);
  EXPECT_NE(invalid_argument_message([&] { terrain_from_map(Eigen::MatrixXd(0, 0), Eigen::MatrixXd(0, 0), kRes, 0, 0); })
                .find("empty"),
            std::string::npos);
  EXPECT_NE(invalid_argument_message([&] { terrain_from_map(b.h, b.v, kRes, std::nan(""), 0); }).find("origin_x"),
            std::string::npos);
  MapTerrainOptions bad;
  bad.sigma_factor = std::nan("");
  EXPECT_NE(invalid_argument_message([&] { bad.validate(); }).find("sigma_factor"), std::string::npos);
  // A fresh ElevationMap is all holes: the same explicit error.
  ernest::perception::ElevationMapOptions eo;
  eo.length = 1.0;
  const ernest::perception::ElevationMap fresh(eo);
  EXPECT_NE(invalid_argument_message([&] { terrain_from_map(fresh); }).find("no observed cell"), std::string::npos);
}

// An unknown region in reach is never a foothold: the stability map finds no IK on the column,
// and a step there is an explicit no-plan. Flat ground seen at 1 cm with a 0.6 m blind square.
TEST(FootfallTerrain, UnknownCellsAreNeverFootholds) {
  const walker::WalkerModel model(walker::sdm_b_parameters());
  const Eigen::Isometry3d body = model.standard_body_pose();
  const Eigen::MatrixXd q = model.standard_configuration();
  const Eigen::Vector3d foot = model.contact_points(body, q).col(0);
  const int n = 601;  // 6 m x 6 m around the foot
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, n), v = Eigen::MatrixXd::Constant(n, n, 1e-4);
  const double x0 = foot.x() - 3.0, y0 = foot.y() - 3.0;
  const Eigen::Vector2d blind(foot.x() + 0.5, foot.y());
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (std::abs(x0 + i * kRes - blind.x()) <= 0.3 && std::abs(y0 + j * kRes - blind.y()) <= 0.3)
        h(i, j) = std::nan(""), v(i, j) = INFINITY;
  const MapTerrain t = terrain_from_map(h, v, kRes, x0, y0);
  StabilityMapOptions mo;
  mo.cell = 0.05;
  StabilityMapper mapper(model, t.terrain, body, q, 0, mo);
  const StabilityMap map = mapper.map();
  int unknown_cells = 0;
  for (Eigen::Index i = 0; i < map.status.rows(); ++i)
    for (Eigen::Index j = 0; j < map.status.cols(); ++j)
      if (t.unknown_at(map.origin_x + i * map.cell, map.origin_y + j * map.cell)) {
        ++unknown_cells;
        EXPECT_EQ(map.status(i, j), static_cast<std::uint8_t>(CellStatus::kUnreachable));
      }
  EXPECT_GT(unknown_cells, 100);
  EXPECT_GT(map.count(CellStatus::kStable), 100);  // the seen ground around it is usable
  StepOptions so;
  so.map.cell = 0.05;
  const StepPlan p = plan_step(model, t.terrain, body, q, 0, blind.x(), blind.y(), so);
  EXPECT_EQ(p.status, PlanStatus::kNoPlan);
  EXPECT_NE(p.reason.find("unreachable"), std::string::npos) << p.reason;
}

// NaN poses throw; every query ends within its budget, solved or with
// the timeout reason (never a hang), here on the hard rock field of the benchmark.
TEST(FootfallTerrain, NanPosesThrowAndPlanningKeepsItsBudget) {
  const walker::WalkerModel model(walker::sdm_b_parameters());
  const Eigen::Isometry3d body = model.standard_body_pose();
  const Eigen::MatrixXd q = model.standard_configuration();
  const Eigen::Matrix3Xd feet = model.contact_points(body, q);
  const HeightMap flat = HeightMap::flat(12, 12, 0.05, 0.0, -6, -6);
  Eigen::Isometry3d nan_body = body;
  nan_body.translation().x() = std::nan("");
  EXPECT_THROW(plan_step(model, flat, nan_body, q, 0, feet(0, 0) + 0.2, feet(1, 0)), std::invalid_argument);
  EXPECT_THROW(LegCollisionChecker(model, flat, nan_body, q, 0), std::invalid_argument);
  Eigen::MatrixXd nan_q = q;
  nan_q(1, 3) = std::nan("");
  EXPECT_THROW(plan_step(model, flat, body, nan_q, 0, feet(0, 0) + 0.2, feet(1, 0)), std::invalid_argument);
  EXPECT_THROW(StabilityMapper(model, flat, body, nan_q, 0), std::invalid_argument);

  RockFieldOptions ro;
  ro.rocks = 40;
  ro.max_height = 0.5;
  const HeightMap rocks = rock_field(ro, feet.topRows<2>());
  StabilityMapOptions mo;
  mo.cell = 0.05;
  StabilityMapper mapper(model, rocks, body, q, 0, mo);
  LegCollisionChecker checker(model, rocks, body, q, 0);
  const Eigen::MatrixXd ends = sample_waypoints(mapper, mapper.map(), checker, 16, 7);
  PlannerOptions po;
  po.time_limit = 0.01;
  for (int k = 0; k < 8; ++k) {
    po.seed = k + 1;
    const PlanResult r = LegPlanner(checker, po).plan(ends.col(2 * k), ends.col(2 * k + 1));
    EXPECT_LT(r.seconds, po.time_limit + 0.5) << "query " << k;  // the budget plus set-up, not a hang
    if (r.status == PlanStatus::kNoPlan) EXPECT_EQ(r.reason, "no path found within the time limit");
  }
}

// The terrain is solid: a leg entirely below the surface collides (FCL's triangle mesh alone is
// a surface and would find nothing to touch), and the same leg above it is free.
TEST(FootfallTerrain, TheTerrainIsSolid) {
  const walker::WalkerModel model(walker::sdm_b_parameters());
  const Eigen::Isometry3d body = model.standard_body_pose();
  const Eigen::MatrixXd q = model.standard_configuration();
  const Eigen::VectorXd up = walker::lift_legs(model, body, q, {0}, 0.3).col(0);
  CollisionOptions o;
  o.environment_clearance = 0.0;
  LegCollisionChecker below(model, HeightMap::flat(12, 12, 0.05, 3.0, -6, -6), body, q, 0, o);
  EXPECT_FALSE(below.valid(up));
  LegCollisionChecker above(model, HeightMap::flat(12, 12, 0.05, -0.5, -6, -6), body, q, 0, o);
  EXPECT_TRUE(above.valid(up));
}
