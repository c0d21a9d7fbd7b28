// Torque-aware FootFall (seed 003 §7.1): the stance torques against walker::stance_loads, the
// limiting cases of the torque-aware stability map (an infinite limit gives the plain map bit for
// bit, a zero limit turns every stable cell overloaded), plan_step refusing an overloaded goal,
// and the peak-torque smoother (no higher peak than its input, collision-free when rechecked).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "ernest/footfall/leg_planner.hpp"
#include "ernest/footfall/scenario.hpp"
#include "ernest/footfall/stability_map.hpp"
#include "ernest/footfall/stance_torque.hpp"
#include "ernest/footfall/step_planner.hpp"
#include "ernest/footfall/torque_smoothing.hpp"
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
bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * std::size_t(a.size())) == 0;
}
}  // namespace

TEST(FootfallTorque, StanceTorquesEqualStanceLoads) {
  Scene s;
  Eigen::Isometry3d body = s.body;
  body.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()).toRotationMatrix();  // tilted
  for (int leg : {0, 3}) {
    StanceTorques t(s.model, body, s.q, leg);
    const TorquePeak down = t.down(s.q.col(leg));
    const walker::StanceLoads all = walker::stance_loads(s.model, body, s.q, {});
    EXPECT_NEAR(down.saturation, all.peak_saturation, 1e-9);
    EXPECT_EQ(down.leg, all.peak_leg);
    EXPECT_EQ(down.joint, all.peak_joint);
    const Eigen::MatrixXd up = walker::lift_legs(s.model, body, s.q, {leg}, 0.2);
    const TorquePeak lifted = t.lifted(up.col(leg));
    const walker::StanceLoads five = walker::stance_loads(s.model, body, up, {leg});
    EXPECT_NEAR(lifted.saturation, five.peak_saturation, 1e-9);
    EXPECT_EQ(lifted.leg, five.peak_leg);
    // A segment's peak includes its ends.
    EXPECT_GE(t.lifted_segment(up.col(leg), s.q.col(leg), 0.05).saturation, lifted.saturation);
  }
  StanceTorques t(s.model, s.body, s.q, 0);
  Eigen::VectorXd nan = s.q.col(0);
  nan[1] = std::nan("");
  EXPECT_THROW(t.down(nan), std::invalid_argument);
}

TEST(FootfallTorque, LimitingCasesOfTheMap) {
  Scene s;
  const HeightMap rocks = rock_field(RockFieldOptions{}, s.feet.topRows<2>());
  StabilityMapOptions plain;
  plain.cell = 0.05;
  const StabilityMap a = StabilityMapper(s.model, rocks, s.body, s.q, 0, plain).map();
  StabilityMapOptions infinite = plain;
  infinite.torques = true;  // evaluated, limit infinity
  const StabilityMap b = StabilityMapper(s.model, rocks, s.body, s.q, 0, infinite).map();
  EXPECT_TRUE(a.status == b.status);
  EXPECT_TRUE(same_bits(a.margin, b.margin)) << "an infinite limit gives today's map bit for bit";
  EXPECT_EQ(a.ik_solves, b.ik_solves);
  EXPECT_TRUE(a.saturation.array().isNaN().all());
  EXPECT_TRUE(std::isnan(a.lift_saturation));
  EXPECT_EQ(b.count(CellStatus::kOverloaded), 0);
  for (Eigen::Index i = 0; i < b.status.rows(); ++i)
    for (Eigen::Index j = 0; j < b.status.cols(); ++j)
      EXPECT_EQ(std::isnan(b.saturation(i, j)), b.status(i, j) == 0);
  EXPECT_GT(b.lift_saturation, 0.0);
  // A zero limit: every stable cell is overloaded, the rest is unchanged.
  StabilityMapOptions zero = plain;
  zero.max_saturation = 0.0;
  const StabilityMap c = StabilityMapper(s.model, rocks, s.body, s.q, 0, zero).map();
  EXPECT_EQ(c.count(CellStatus::kStable), 0);
  EXPECT_EQ(c.count(CellStatus::kOverloaded), a.count(CellStatus::kStable));
  EXPECT_EQ(c.count(CellStatus::kUnstable), a.count(CellStatus::kUnstable));
  // A limit in between splits the stable cells by their peak torque.
  double lo = 1e9, hi = 0.0;
  for (Eigen::Index k = 0; k < b.status.size(); ++k)
    if (b.status(k) == 2) lo = std::min(lo, b.saturation(k)), hi = std::max(hi, b.saturation(k));
  StabilityMapOptions mid = plain;
  mid.max_saturation = 0.5 * (lo + hi);
  const StabilityMap d = StabilityMapper(s.model, rocks, s.body, s.q, 0, mid).map();
  EXPECT_GT(d.count(CellStatus::kOverloaded), 0);
  EXPECT_GT(d.count(CellStatus::kStable), 0);
  for (Eigen::Index k = 0; k < d.status.size(); ++k) {
    if (d.status(k) == 2) EXPECT_LE(d.saturation(k), mid.max_saturation);
    if (d.status(k) == 3) EXPECT_GT(d.saturation(k), mid.max_saturation);
  }
  StabilityMapOptions bad = plain;
  for (double v : {std::nan(""), -0.1}) {
    bad.max_saturation = v;
    EXPECT_NE(invalid_argument_message([&] { bad.validate(); }).find("max_saturation"), std::string::npos);
  }
  SmoothingOptions so;
  so.torque_resolution = 0.0;
  EXPECT_NE(invalid_argument_message([&] { so.validate(); }).find("torque_resolution"), std::string::npos);
}

TEST(FootfallTorque, PlanStepRefusesAnOverloadedGoalAndSmoothsForTorque) {
  Scene s;
  const HeightMap rocks = rock_field(RockFieldOptions{}, s.feet.topRows<2>());
  StepOptions so;
  so.map.cell = 0.05;
  so.map.torques = true;
  const double gx = s.feet(0, 0) + 0.35, gy = s.feet(1, 0);
  const StepPlan p = plan_step(s.model, rocks, s.body, s.q, 0, gx, gy, so);
  ASSERT_EQ(p.status, PlanStatus::kSolved) << p.reason;
  ASSERT_TRUE(std::isfinite(p.goal_saturation));
  EXPECT_GT(p.path_saturation, 0.0);
  so.map.max_saturation = 0.99 * p.goal_saturation;
  const StepPlan refused = plan_step(s.model, rocks, s.body, s.q, 0, gx, gy, so);
  EXPECT_EQ(refused.status, PlanStatus::kNoPlan);
  EXPECT_NE(refused.reason.find("overloads leg"), std::string::npos) << refused.reason;
  // A limit between the goal's peak and the swing's refuses the swing.
  if (p.path_saturation > p.goal_saturation + 1e-6) {
    so.map.max_saturation = 0.5 * (p.goal_saturation + p.path_saturation);
    const StepPlan swing = plan_step(s.model, rocks, s.body, s.q, 0, gx, gy, so);
    EXPECT_NE(swing.reason.find("the swing overloads"), std::string::npos) << swing.reason;
  }
  // The peak-torque smoother on SBL plans among rocks: never a higher peak than its input,
  // collision-free when rechecked densely without clearance.
  StabilityMapOptions mo;
  mo.cell = 0.05;
  StabilityMapper mapper(s.model, rocks, s.body, s.q, 0, mo);
  LegCollisionChecker checker(s.model, rocks, s.body, s.q, 0);
  CollisionOptions exact_o;
  exact_o.environment_clearance = exact_o.own_leg_clearance = 0.0;
  exact_o.clearance_table = Eigen::MatrixXd::Zero(7, 8);
  LegCollisionChecker exact(s.model, rocks, s.body, s.q, 0, exact_o);
  StanceTorques torques(s.model, s.body, s.q, 0);
  const Eigen::MatrixXd ends = sample_waypoints(mapper, mapper.map(), checker, 12, 3);
  for (int k = 0; k < 6; ++k) {
    PlannerOptions po;
    po.seed = 10 + k;
    const PlanResult r = LegPlanner(checker, po).plan(ends.col(2 * k), ends.col(2 * k + 1));
    if (r.status != PlanStatus::kSolved) continue;
    const SmoothingResult t = smooth_path_for_torque(checker, torques, r.path);
    EXPECT_LE(t.peak_saturation, t.initial_peak_saturation + 1e-3) << "query " << k;
    EXPECT_NEAR(t.initial_peak_saturation, torques.lifted_path(r.path, 0.05).saturation, 1e-12);
    EXPECT_TRUE(t.path.col(0).isApprox(r.path.col(0)));
    EXPECT_TRUE(t.path.rightCols<1>().isApprox(r.path.rightCols<1>()));
    EXPECT_EQ(first_colliding_edge(exact, t.path, 1e-3), -1) << "query " << k;
  }
  LegCollisionChecker other(s.model, rocks, s.body, s.q, 1);
  EXPECT_NE(invalid_argument_message([&] { smooth_path_for_torque(other, torques, ends.leftCols(2)); }).find("different legs"),
            std::string::npos);
}
