// FootFall planning core (seed 003 §3.3–3.4, §4.1, §5.1): collision checks against closed-form
// heights, the stability map against the statics functions and the robot's symmetry, the sag's
// equilibrium, SBL plans re-checked densely without clearance, seeded reproducibility, the
// smoother, and the explicit no-plan answers.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "ernest/footfall/leg_planner.hpp"
#include "ernest/footfall/path_smoothing.hpp"
#include "ernest/footfall/scenario.hpp"
#include "ernest/footfall/stability_map.hpp"
#include "ernest/footfall/step_planner.hpp"
#include "ernest/footfall/swing_sag.hpp"
#include "ernest/statics/stability.hpp"
#include "ernest/walker/self_collision.hpp"
#include "ernest/walker/stance_loads.hpp"
#include "test_util.hpp"

using namespace ernest::footfall;
using ernest::dynamics::HeightMap;
using ernest::testing::invalid_argument_message;
namespace walker = ernest::walker;

namespace {

struct Scene {
  walker::WalkerModel model{walker::sdm_b_parameters()};
  Eigen::Isometry3d body = model.standard_body_pose();
  Eigen::MatrixXd q = model.standard_configuration();
  Eigen::Matrix3Xd feet = model.contact_points(body, q);
};

CollisionOptions zero_clearance(int n) {
  CollisionOptions o;
  o.environment_clearance = o.own_leg_clearance = 0.0;
  o.clearance_table = Eigen::MatrixXd::Zero(n + 1, n + 2);
  return o;
}

}  // namespace

TEST(Footfall, OptionsNameTheField) {
  CollisionOptions c;
  c.environment_clearance = -0.1;
  EXPECT_NE(invalid_argument_message([&] { c.validate(6); }).find("environment_clearance"), std::string::npos);
  CollisionOptions t;
  t.clearance_table = Eigen::MatrixXd::Zero(3, 3);
  EXPECT_NE(invalid_argument_message([&] { t.validate(6); }).find("clearance_table"), std::string::npos);
  // a joint count that would size a huge or negative table is refused, not a bad_alloc
  for (int joints : {-5, 0, 1 << 20})
    EXPECT_NE(invalid_argument_message([&] { default_clearance_table(joints); }).find("joints"),
              std::string::npos);
  EXPECT_EQ(default_clearance_table(6).rows(), 7);
  PlannerOptions p;
  p.epsilon = std::nan("");
  EXPECT_NE(invalid_argument_message([&] { p.validate(); }).find("epsilon"), std::string::npos);
  StabilityMapOptions m;
  m.cell = 0.0;
  EXPECT_NE(invalid_argument_message([&] { m.validate(); }).find("cell"), std::string::npos);
}

// Terrain clearance against a flat plane: the wheel's lowest point at height h is free exactly
// when h exceeds the environment clearance (closed form, independent of FCL).
TEST(Footfall, TerrainClearanceMatchesTheHeightAboveAFlatPlane) {
  Scene s;
  const HeightMap flat = HeightMap::flat(12, 12, 0.05, 0.0, -6, -6);
  CollisionOptions o;
  o.environment_clearance = 0.05;
  LegCollisionChecker checker(s.model, flat, s.body, s.q, 0, o);
  EXPECT_FALSE(checker.valid(s.q.col(0))) << "the wheel stands on the ground";
  EXPECT_TRUE(checker.valid(s.q.col(0), false)) << "without the wheel the standard leg is free";
  for (double h : {0.03, 0.045, 0.055, 0.08}) {
    const Eigen::MatrixXd up = walker::lift_legs(s.model, s.body, s.q, {0}, h);
    EXPECT_EQ(checker.valid(up.col(0)), h > 0.05) << "wheel " << h << " m above the plane";
  }
}

// Against walker::self_collisions (the whole-robot check of cpp/walker) on random leg-0
// configurations with zero clearances over ground far below: the same verdict every time.
TEST(Footfall, SelfCollisionAgreesWithTheWalkerCheck) {
  Scene s;
  const HeightMap deep = HeightMap::flat(12, 12, 0.1, -10.0, -6, -6);
  LegCollisionChecker checker(s.model, deep, s.body, s.q, 0, zero_clearance(s.model.joints_per_leg()));
  std::mt19937_64 rng(3);
  const Eigen::VectorXd lo = s.model.lower_limits(), hi = s.model.upper_limits();
  int colliding = 0;
  for (int k = 0; k < 300; ++k) {
    Eigen::MatrixXd q = s.q;
    for (int i = 0; i < s.model.joints_per_leg(); ++i)
      q(i, 0) = std::uniform_real_distribution<double>(lo[i], hi[i])(rng);
    bool walker_hit = false;
    for (const auto& p : walker::self_collisions(s.model, q, 0.0)) walker_hit |= p.leg_a == 0 || p.leg_b == 0;
    colliding += walker_hit;
    EXPECT_EQ(checker.valid(q.col(0)), !walker_hit) << "sample " << k;
  }
  EXPECT_GT(colliding, 10);
  EXPECT_LT(colliding, 290);
  Eigen::VectorXd outside = s.q.col(0);
  outside[1] = hi[1] + 0.1;
  EXPECT_FALSE(checker.valid(outside)) << "outside the joint limits";
}

// The map's margin of a cell equals the statics margins of the stance built through the public
// walker API; flat ground and the leg on the x axis make the map symmetric in y.
TEST(Footfall, StabilityMapAgreesWithStaticsAndIsSymmetric) {
  Scene s;
  const HeightMap flat = HeightMap::flat(12, 12, 0.05, 0.0, -6, -6);
  StabilityMapOptions mo;
  mo.cell = 0.05;
  StabilityMapper mapper(s.model, flat, s.body, s.q, 0, mo);
  const StabilityMap m = mapper.map();
  EXPECT_FALSE(m.nesm);
  EXPECT_TRUE(m.start_waypoint_reachable);
  EXPECT_GT(m.count(CellStatus::kStable), 50);
  EXPECT_GT(m.count(CellStatus::kUnreachable), 50);
  int asymmetric = 0, reachable = 0;
  const Eigen::Index ny = m.status.cols();
  for (Eigen::Index i = 0; i < m.status.rows(); ++i)
    for (Eigen::Index j = 0; j < ny; ++j) {
      reachable += m.status(i, j) != 0;
      asymmetric += m.status(i, j) != m.status(i, ny - 1 - j);
      if (m.status(i, j) == 0) continue;
      const double x = m.origin_x + i * m.cell, y = m.origin_y + j * m.cell;
      EXPECT_LE(std::hypot(x - m.hip.x(), y - m.hip.y()), m.reach + 1e-9);
    }
  EXPECT_LT(asymmetric, 0.03 * reachable);
  // One cell recomputed independently.
  const double gx = s.feet(0, 0) + 0.3, gy = 0.2;
  const CellEvaluation e = mapper.evaluate(gx, gy, s.q.col(0));
  ASSERT_NE(e.status, CellStatus::kUnreachable);
  Eigen::MatrixXd q2 = s.q;
  q2.col(0) = e.q;
  const Eigen::Matrix3Xd c = s.model.contact_points(s.body, q2);
  EXPECT_NEAR(c(0, 0), gx, 1e-3);
  EXPECT_NEAR(c(1, 0), gy, 1e-3);
  EXPECT_NEAR(c(2, 0), 0.0, 1e-3);
  const Eigen::Vector3d cg = s.model.center_of_mass(s.body, q2);
  EXPECT_LT((cg - e.cg).norm(), 1e-9);
  const auto margins = ernest::statics::stability_margins(c, cg, Eigen::Vector3d(0, 0, -9.81));
  EXPECT_NEAR(e.margin, margins.ssm_cps, 1e-9);
  // The lifted waypoint is 0.2 m straight above.
  const Eigen::Vector3d above = s.body * s.model.contact_point(0, e.q_above);
  EXPECT_NEAR(above.z(), mo.lift_height, 1e-3);
  EXPECT_NEAR(std::hypot(above.x() - gx, above.y() - gy), 0.0, 1e-3);
}

TEST(Footfall, SlopedStanceUsesNesm) {
  Scene s;
  const HeightMap slope = HeightMap::slope(0.2, 12, 12, 0.05, -6, -6);
  Eigen::Isometry3d body = s.body;
  body.translation().z() += 0.0;
  // Feet on a 11.5° plane: put the body on it rigidly (rotate about y).
  body.linear() = Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  StabilityMapOptions mo;
  mo.cell = 0.1;
  StabilityMapper mapper(s.model, slope, body, s.q, 0, mo);
  EXPECT_TRUE(mapper.nesm());
}

// The swing stance's sag: the lifted foot carries nothing, the others carry the weight, the
// swing leg's hip sags more than the opposite one.
TEST(Footfall, SwingSagIsInEquilibriumAndDropsTheSwingSide) {
  Scene s;
  const SwingSag sag = predict_swing_sag(s.model, s.body, s.q, 0);
  ASSERT_EQ(sag.status, ernest::statics::SagStatus::Converged);
  EXPECT_NEAR(sag.forces.col(0).norm(), 0.0, 1e-9);
  EXPECT_NEAR(sag.forces.row(2).sum(), s.model.params().total_mass() * 9.81, 1e-3 * s.model.params().total_mass());
  EXPECT_GT(sag.hip_drop[0], sag.hip_drop[3] + 1e-3);
  EXPECT_GT(sag.hip_drop[0], 0.0);
  EXPECT_LT(sag.hip_drop[0], 0.2);
  SwingSagOptions stiff;
  stiff.stiffness = 6e6;  // 100 × stiffer: 100 × less sag (linear springs)
  const SwingSag s2 = predict_swing_sag(s.model, s.body, s.q, 0, stiff);
  EXPECT_NEAR(s2.hip_drop[0] * 100.0, sag.hip_drop[0], 0.02 * sag.hip_drop[0]);
  Eigen::Isometry3d bad = s.body;
  bad.translation().x() = std::nan("");
  EXPECT_THROW(predict_swing_sag(s.model, bad, s.q, 0), std::invalid_argument);
}

// §3.4.1: random feasible queries among rocks; every SBL plan and its smoothed version are free
// when re-checked every 1e-3 rad without clearance; smoothing never lengthens a path.
TEST(Footfall, PlansAmongRocksAreCollisionFreeWhenRecheckedDensely) {
  Scene s;
  const HeightMap rocks = rock_field(RockFieldOptions{}, s.feet.topRows<2>());
  StabilityMapOptions mo;
  mo.cell = 0.05;
  StabilityMapper mapper(s.model, rocks, s.body, s.q, 0, mo);
  const StabilityMap map = mapper.map();
  LegCollisionChecker checker(s.model, rocks, s.body, s.q, 0);
  LegCollisionChecker exact(s.model, rocks, s.body, s.q, 0, zero_clearance(s.model.joints_per_leg()));
  const int queries = 20;
  const Eigen::MatrixXd ends = sample_waypoints(mapper, map, checker, 2 * queries, 11);
  PlannerOptions po;
  int solved = 0;
  for (int k = 0; k < queries; ++k) {
    po.seed = k + 1;
    LegPlanner planner(checker, po);
    const PlanResult r = planner.plan(ends.col(2 * k), ends.col(2 * k + 1));
    if (r.status != PlanStatus::kSolved) {
      EXPECT_FALSE(r.reason.empty());
      continue;
    }
    ++solved;
    EXPECT_TRUE(r.path.col(0).isApprox(ends.col(2 * k)));
    EXPECT_TRUE(r.path.rightCols<1>().isApprox(ends.col(2 * k + 1)));
    EXPECT_EQ(first_colliding_edge(exact, r.path, 1e-3), -1) << "query " << k;
    const SmoothingResult sm = smooth_path(checker, r.path);
    EXPECT_LE(sm.length, r.length + 1e-12);
    EXPECT_NEAR(sm.initial_length, r.length, 1e-12);
    EXPECT_TRUE(sm.path.col(0).isApprox(r.path.col(0)));
    EXPECT_TRUE(sm.path.rightCols<1>().isApprox(r.path.rightCols<1>()));
    EXPECT_EQ(first_colliding_edge(exact, sm.path, 1e-3), -1) << "smoothed query " << k;
  }
  EXPECT_GE(solved, queries - 1);
}

TEST(Footfall, SameSeedSamePlan) {
  Scene s;
  const HeightMap rocks = rock_field(RockFieldOptions{}, s.feet.topRows<2>());
  StabilityMapOptions mo;
  mo.cell = 0.05;
  StabilityMapper mapper(s.model, rocks, s.body, s.q, 0, mo);
  LegCollisionChecker checker(s.model, rocks, s.body, s.q, 0);
  const Eigen::MatrixXd ends = sample_waypoints(mapper, mapper.map(), checker, 2, 5);
  PlannerOptions po;
  po.seed = 42;
  const PlanResult a = LegPlanner(checker, po).plan(ends.col(0), ends.col(1));
  LegPlanner again(checker, po);
  const PlanResult b = again.plan(ends.col(0), ends.col(1));
  const PlanResult c = again.plan(ends.col(0), ends.col(1));  // the same planner, queried twice
  ASSERT_EQ(a.status, PlanStatus::kSolved);
  ASSERT_EQ(a.path.cols(), b.path.cols());
  ASSERT_EQ(a.path.cols(), c.path.cols());
  EXPECT_EQ((a.path - b.path).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((a.path - c.path).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Footfall, NoPlanAnswersAndErrors) {
  Scene s;
  const HeightMap flat = HeightMap::flat(12, 12, 0.05, 0.0, -6, -6);
  LegCollisionChecker checker(s.model, flat, s.body, s.q, 0);
  const Eigen::MatrixXd up = walker::lift_legs(s.model, s.body, s.q, {0}, 0.3);
  LegPlanner planner(checker);
  Eigen::VectorXd nan = up.col(0);
  nan[2] = std::nan("");
  EXPECT_THROW(planner.plan(nan, up.col(0)), std::invalid_argument);
  EXPECT_THROW(planner.plan(up.col(0), Eigen::VectorXd::Zero(3)), std::invalid_argument);
  const PlanResult r = planner.plan(s.q.col(0), up.col(0));  // the wheel on the ground
  EXPECT_EQ(r.status, PlanStatus::kNoPlan);
  EXPECT_EQ(r.reason, "start in collision");
  EXPECT_EQ(planner.plan(up.col(0), s.q.col(0)).reason, "goal in collision");
  PlannerOptions tiny;
  tiny.time_limit = 1e-4;  // the budget ends the search: an explicit answer, no hang
  const PlanResult t = LegPlanner(checker, tiny).plan(up.col(0), walker::lift_legs(s.model, s.body, s.q, {0}, 0.6).col(0));
  if (t.status == PlanStatus::kNoPlan) EXPECT_EQ(t.reason, "no path found within the time limit");
  EXPECT_LT(t.seconds, 0.5);
  // plan_step: far goal, NaN goal, an unstable goal (no cell clears a 5 m margin).
  StepOptions so;
  so.map.cell = 0.05;
  EXPECT_NE(plan_step(s.model, flat, s.body, s.q, 0, 9.0, 0.0, so).reason.find("unreachable"), std::string::npos);
  EXPECT_THROW(plan_step(s.model, flat, s.body, s.q, 0, std::nan(""), 0.0, so), std::invalid_argument);
  so.map.min_margin = 5.0;
  const StepPlan unstable = plan_step(s.model, flat, s.body, s.q, 0, s.feet(0, 0) + 0.2, 0.0, so);
  EXPECT_EQ(unstable.status, PlanStatus::kNoPlan);
  EXPECT_NE(unstable.reason.find("unstable"), std::string::npos) << unstable.reason;
}

// §4.1/§5.1: a step planned against the sagged pose: the path runs from the start through the
// waypoints above start and goal to the goal; the waypoints clear the real ground by the lift.
TEST(Footfall, SagCompensatedStep) {
  Scene s;
  const HeightMap rocks = rock_field(RockFieldOptions{}, s.feet.topRows<2>());
  StepOptions so;
  so.map.cell = 0.05;
  const double gx = s.feet(0, 0) + 0.35, gy = s.feet(1, 0);
  const StepPlan p = plan_step(s.model, rocks, s.body, s.q, 0, gx, gy, so);
  ASSERT_EQ(p.status, PlanStatus::kSolved) << p.reason;
  EXPECT_TRUE(p.path.col(0).isApprox(s.q.col(0)));
  EXPECT_TRUE(p.path.rightCols<1>().isApprox(p.q_goal));
  EXPECT_TRUE(p.path.col(1).isApprox(p.q_start_above));
  EXPECT_TRUE(p.path.col(p.path.cols() - 2).isApprox(p.q_goal_above));
  EXPECT_FALSE(p.planning_body.isApprox(s.body)) << "planned against the sagged pose";
  const Eigen::Vector3d up = p.planning_body * s.model.contact_point(0, p.q_goal_above);
  EXPECT_NEAR(up.z() - p.goal.z(), so.map.lift_height, 1e-3);
  LegCollisionChecker exact(s.model, rocks, p.planning_body, s.q, 0, zero_clearance(s.model.joints_per_leg()));
  EXPECT_EQ(first_colliding_edge(exact, p.path, 1e-3, 1), -1);
  const Eigen::Vector3d touchdown = s.body * s.model.contact_point(0, p.q_goal);
  EXPECT_NEAR((touchdown - p.goal).norm(), 0.0, 1e-3);
}
