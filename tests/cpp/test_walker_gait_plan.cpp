// FootFall's skeleton gait (seed 003 §5.3.1): reverse-wave order, step lengths by successive IK,
// body shifts with all feet down, periodic after the second cycle on flat ground, every stance
// statically stable.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "ernest/statics/stability.hpp"
#include "ernest/walker/gait_planner.hpp"
#include "ernest/walker/leg_ik.hpp"
#include "test_util.hpp"

using namespace ernest::walker;
using ernest::testing::invalid_argument_message;

namespace {
constexpr double kPi = 3.14159265358979323846;
}

TEST(WalkerGaitPlan, ReverseWaveIsFrontToRearLeftFirst) {
  const WalkerModel m(sdm_b_parameters());
  // Legs counter-clockwise from +x: travelling +x, leg 0 is in front, 1 front-left, 5 front-right.
  EXPECT_EQ(reverse_wave_sequence(m, 0.0), (std::vector<int>{0, 1, 5, 2, 4, 3}));
  // Travelling +y: legs 1 and 2 in front, 2 is on the left of +y (x < 0).
  EXPECT_EQ(reverse_wave_sequence(m, 0.5 * kPi), (std::vector<int>{2, 1, 3, 0, 4, 5}));
  // Travelling 30°: between legs 0 and 1, 1 on the left.
  EXPECT_EQ(reverse_wave_sequence(m, kPi / 6), (std::vector<int>{1, 0, 2, 5, 3, 4}));
}

TEST(WalkerGaitPlan, BecomesPeriodicAfterTheSecondCycleWithEveryStanceStable) {
  const WalkerModel m(sdm_b_parameters());
  GaitPlannerOptions o;
  o.cycles = 5;
  // Longer than the front leg can step from the standard stance (0.752 m: reach), so the gait
  // starts with a transient.
  o.max_step = 0.78;
  const double L = o.max_step, tol = 2.0 * o.search_tolerance;
  const GaitPlan p = plan_gait(m, m.standard_body_pose().translation(), m.standard_configuration(), o);
  ASSERT_EQ(p.events.size(), 60u);
  ASSERT_EQ(p.step_lengths.rows(), 5);
  // Every leg but the first steps the full L, and every shift is a sixth of the step before it
  // (the body follows the feet's centroid).
  for (int c = 0; c < 5; ++c)
    for (int i = 0; i < 6; ++i) {
      if (i > 0) EXPECT_NEAR(p.step_lengths(c, i), L, tol) << c << " " << i;
      EXPECT_NEAR(p.shift_lengths(c, i), p.step_lengths(c, i) / 6.0, tol) << c << " " << i;
    }
  // The front leg steps to its reach, a fixed offset ahead of the body; the body advanced
  // (step_{c-1} + 5 L) / 6 in the cycle before, so L - step_c = (L - step_{c-1}) / 6: the
  // transient (2.8 cm) decays six-fold a cycle. Closed form vs the planner's successive IK:
  EXPECT_LT(p.step_lengths(0, 0), L - 0.02);
  for (int c = 1; c < 5; ++c)
    EXPECT_NEAR(L - p.step_lengths(c, 0), (L - p.step_lengths(c - 1, 0)) / 6.0, tol) << c;
  // §5.3.1: "After the second gait cycle ... the motion converges to a regular, periodic pattern.
  // At this point all the body shifts are of equal length, and so are the steps": from cycle 3 on
  // (cycles 4 and 5 against the one before) every step and every shift repeats the previous
  // cycle's, and the steps (shifts) of a cycle from the third on agree with each other, to 1 mm.
  const double periodic = 1e-3;
  for (int c = 2; c < 5; ++c) {
    EXPECT_LT(p.step_lengths.row(c).maxCoeff() - p.step_lengths.row(c).minCoeff(), periodic) << c;
    EXPECT_LT(p.shift_lengths.row(c).maxCoeff() - p.shift_lengths.row(c).minCoeff(), periodic) << c;
    if (c == 2) continue;
    EXPECT_LT((p.step_lengths.row(c) - p.step_lengths.row(c - 1)).cwiseAbs().maxCoeff(), periodic) << c;
    EXPECT_LT((p.shift_lengths.row(c) - p.shift_lengths.row(c - 1)).cwiseAbs().maxCoeff(), periodic) << c;
  }
  // Not yet in cycle 2 (the comparison is not vacuous).
  EXPECT_GT((p.step_lengths.row(1) - p.step_lengths.row(0)).cwiseAbs().maxCoeff(), 0.01);
  // "Largest step the IK allows", checked with an independent multi-start IK (more seeds): the
  // reported goal is reachable and 1 cm further is not.
  const GaitEvent& first = p.events[0];
  IkOptions wide;
  wide.seeds = 64;
  LegIk ik(m, wide);
  const Eigen::Vector3d body = first.body_before;
  for (double extra : {0.0, 0.01}) {
    const Eigen::Vector3d goal = first.feet_after.col(0) + Eigen::Vector3d(extra, 0.0, 0.0);
    const int reachable = ik.solve(0, upright_foot_pose(m, goal - body, 0.0), first.q_before.col(0)).status ==
                                  IkStatus::kSolved &&
                          ik.solve(0, upright_foot_pose(m, goal + Eigen::Vector3d(0, 0, o.lift_height) - body, 0.0),
                                   first.q_before.col(0)).status == IkStatus::kSolved;
    EXPECT_EQ(reachable, extra == 0.0) << "extra " << extra;
  }
  // Every event, recomputed here from its configurations with cpp/statics: the wheels are where
  // the plan says, only the stepping foot moves (along the heading), and every stance during a
  // step (the leg at the waypoint above its start and above its goal) has SSM > 0.
  double min_ssm = 1e9;
  for (const GaitEvent& e : p.events) {
    Eigen::Isometry3d b = Eigen::Isometry3d::Identity();
    b.translation() = e.body_after;
    EXPECT_LT((m.contact_points(b, e.q_after) - e.feet_after).cwiseAbs().maxCoeff(), 1e-6);
    const Eigen::Matrix3Xd moved = e.feet_after - e.feet_before;
    if (e.kind == GaitEvent::kShift) {
      EXPECT_LT(moved.cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_NEAR((e.body_after - e.body_before).x(), e.length, 1e-12);
      // the body ends over the feet's centroid along the travel (no leg limited the shift)
      EXPECT_NEAR(e.body_after.x(), e.feet_after.row(0).mean(), tol);
      continue;
    }
    EXPECT_NEAR(moved(0, e.leg), e.length, 1e-12);
    EXPECT_LT(moved.cwiseAbs().sum() - e.length, 1e-12);
    b.translation() = e.body_before;
    for (const Eigen::VectorXd* ql : {&e.q_lift_start, &e.q_lift_goal}) {
      Eigen::MatrixXd q = e.q_before;
      q.col(e.leg) = *ql;
      Eigen::Matrix3Xd loaded(3, 5);
      for (int k = 0, c = 0; k < 6; ++k)
        if (k != e.leg) loaded.col(c++) = e.feet_before.col(k);
      const double ssm = ernest::statics::stability_margins(loaded, m.center_of_mass(b, q),
                                                            Eigen::Vector3d(0, 0, -9.81)).ssm;
      EXPECT_GT(ssm, 0.0);
      EXPECT_GE(ssm, e.support_margin - 1e-9);
      min_ssm = std::min(min_ssm, ssm);
    }
  }
  // The body travelled what the feet did: one step length per cycle in the periodic regime.
  const GaitEvent& last = p.events.back();
  EXPECT_NEAR(last.body_after.x() - p.events[47].body_after.x(), p.step_lengths.row(4).mean(), tol);
  std::printf("front leg's step per cycle: %.4f %.4f %.4f %.4f %.4f m (others %.4f m); min SSM %.3f m; "
              "%d IK tests, %.3f s\n",
              p.step_lengths(0, 0), p.step_lengths(1, 0), p.step_lengths(2, 0), p.step_lengths(3, 0),
              p.step_lengths(4, 0), p.step_lengths(4, 1), min_ssm, p.ik_tests, p.seconds);
}

TEST(WalkerGaitPlan, InvalidOptionsAndInputNameTheField) {
  const WalkerModel m(sdm_b_parameters());
  const Eigen::Vector3d body = m.standard_body_pose().translation();
  GaitPlannerOptions o;
  o.max_step = std::nan("");
  EXPECT_NE(invalid_argument_message([&] { plan_gait(m, body, m.standard_configuration(), o); }).find("max_step"),
            std::string::npos);
  o = GaitPlannerOptions{};
  o.sequence = {0, 1, 2, 3, 4, 4};
  EXPECT_NE(invalid_argument_message([&] { o.validate(6); }).find("sequence"), std::string::npos);
  o = GaitPlannerOptions{};
  o.cycles = 0;
  EXPECT_NE(invalid_argument_message([&] { o.validate(6); }).find("cycles"), std::string::npos);
  o = GaitPlannerOptions{};
  EXPECT_NE(invalid_argument_message([&] {
              plan_gait(m, Eigen::Vector3d(0, 0, std::nan("")), m.standard_configuration(), o);
            }).find("body_position"),
            std::string::npos);
  // The wheels must start on the ground.
  EXPECT_NE(invalid_argument_message([&] { plan_gait(m, body + Eigen::Vector3d(0, 0, 0.1), m.standard_configuration(), o); })
                .find("ground"),
            std::string::npos);
}
