// Weight distribution with legs lifted (seed 003 §5.3.3, Fig. 16) against the closed-form
// distribution on a regular hexagon, and the sway gait (§5.3.2, Fig. 15) with a solver-free
// optimality check.
#include <gtest/gtest.h>

#include <cmath>

#include "ernest/walker/sway_gait.hpp"
#include "test_util.hpp"

using namespace ernest::walker;
using ernest::testing::invalid_argument_message;

TEST(WalkerLoads, OneAndTwoLegsLiftedMatchTheClosedFormDistribution) {
  // Feet on a regular hexagon, CG on its axis, vertical loads linear in position (the
  // zero-interaction distribution): one foot lifted leaves its neighbours 5/18 of the weight, the
  // two next ones 1/6 and the opposite one 1/9; two opposed feet lifted leave 1/4 on each.
  const WalkerModel m(sdm_b_parameters());
  const Eigen::Isometry3d body = m.standard_body_pose();
  const double weight = m.params().total_mass() * m.params().gravity;
  const Eigen::MatrixXd q1 = lift_legs(m, body, m.standard_configuration(), {0}, 0.2);
  const Eigen::MatrixXd q2 = lift_legs(m, body, m.standard_configuration(), {0, 3}, 0.2);
  EXPECT_NEAR((m.contact_points(body, q1).col(0) - m.contact_points(body, m.standard_configuration()).col(0)).z(),
              0.2, 1e-7);
  const StanceLoads one = stance_loads(m, body, q1, {0});
  const StanceLoads two = stance_loads(m, body, q2, {0, 3});
  // The CG moves a little with the raised leg; the closed form holds to that (< 0.5 %).
  const double expected_one[6] = {0.0, 5.0 / 18, 1.0 / 6, 1.0 / 9, 1.0 / 6, 5.0 / 18};
  const double expected_two[6] = {0.0, 0.25, 0.25, 0.0, 0.25, 0.25};
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(one.reactions(2, k) / weight, expected_one[k], 5e-3) << k;
    EXPECT_NEAR(two.reactions(2, k) / weight, expected_two[k], 5e-3) << k;
  }
  for (const StanceLoads* s : {&one, &two}) {
    EXPECT_LT((s->reactions.rowwise().sum() - Eigen::Vector3d(0, 0, weight)).norm(), 1e-9 * weight);
    EXPECT_LT(s->equilibrium_residual, 1e-12);
  }
  // The lifted leg holds only its own links: its torques are g(q).
  const Eigen::VectorXd g0 = m.joint_torques(0, q1.col(0), Eigen::Vector3d::Zero());
  EXPECT_LT((one.torques.col(0) - g0).norm(), 1e-9);
  // §5.3.3 / Fig. 16: the mean load is higher with two legs lifted, the peak load and the peak
  // torque fraction lower; with the hip pitch limit calibrated to Fig. 16(a)'s 50.28 %, (b) reads
  // 43.1 % (paper 43.43 %).
  EXPECT_GT(two.mean_force, one.mean_force);
  EXPECT_LT(two.peak_force, one.peak_force);
  EXPECT_LT(two.peak_saturation, one.peak_saturation);
  EXPECT_NEAR(one.peak_saturation, 0.5028, 0.01);
  EXPECT_NEAR(two.peak_saturation, 0.4343, 0.01);
  EXPECT_EQ(m.params().joints[one.peak_joint].name, "hip_pitch");
  EXPECT_TRUE(one.peak_leg == 1 || one.peak_leg == 5);
  // Input errors name the problem.
  EXPECT_NE(invalid_argument_message([&] { stance_loads(m, body, q1, {0, 0}); }).find("twice"), std::string::npos);
  EXPECT_NE(invalid_argument_message([&] { stance_loads(m, body, q1, {6}); }).find("lifted leg 6"), std::string::npos);
  EXPECT_NE(invalid_argument_message([&] { stance_loads(m, body, q1, {0, 1, 2, 3}); }).find("three"),
            std::string::npos);
}

TEST(WalkerSwayGait, OptionsRefuseALegCountTheyCannotHold) {
  const SwayGaitOptions o;
  o.validate(6);
  for (int legs : {-2147483647 - 1, 0, 1 << 20})
    EXPECT_NE(invalid_argument_message([&] { o.validate(legs); }).find("legs"), std::string::npos);
}

TEST(WalkerSwayGait, LowersEveryPhasePeakWithFootfallsFixed) {
  const WalkerModel m(sdm_b_parameters());
  SwayGaitOptions o;
  const SwayGaitResult r = optimise_sway_gait(m, o);
  ASSERT_EQ(r.reference.size(), 6u);
  double ref_peak = 0.0, sway_peak = 0.0;
  for (std::size_t k = 0; k < 6; ++k) {
    const GaitPhase& a = r.reference[k];
    const GaitPhase& b = r.sway[k];
    ASSERT_TRUE(a.reachable && b.reachable);
    EXPECT_EQ(a.lifted_leg, o.sequence[k]);
    EXPECT_LE(b.peak_saturation, a.peak_saturation + 1e-12);
    EXPECT_GE(b.support_margin, o.min_support_margin - 1e-6);
    EXPECT_LE(b.displacement.head<2>().cwiseAbs().maxCoeff(), o.max_shift_xy + 1e-9);
    // Footfalls fixed: the loaded wheels touch the same world points in both gaits.
    Eigen::Isometry3d ba = Eigen::Isometry3d::Identity(), bb = Eigen::Isometry3d::Identity();
    ba.translation() = a.body_position;
    bb.translation() = b.body_position;
    const Eigen::Matrix3Xd ca = m.contact_points(ba, a.q_lift_off), cb = m.contact_points(bb, b.q_lift_off);
    for (int leg = 0; leg < 6; ++leg) EXPECT_LT((ca.col(leg) - cb.col(leg)).norm(), 1e-6);
    // The reported phase is what evaluate_gait_phase gives at that displacement.
    EXPECT_NEAR(evaluate_gait_phase(m, o, static_cast<int>(k), b.displacement).peak_saturation,
                b.peak_saturation, 1e-9);
    ref_peak = std::max(ref_peak, a.peak_saturation);
    sway_peak = std::max(sway_peak, b.peak_saturation);
  }
  EXPECT_NEAR(r.reference_margin, 1.0 - ref_peak, 1e-12);
  EXPECT_NEAR(r.sway_margin, 1.0 - sway_peak, 1e-12);
  // Paper §5.3.2: over 20 % better; here the worst phase's peak falls by more than 20 %.
  EXPECT_LT(sway_peak, 0.8 * ref_peak);
  EXPECT_NEAR(r.peak_reduction, 1.0 - sway_peak / ref_peak, 1e-12);
  EXPECT_GT(r.improvement, 0.2);
  // Local optimality, checked without the solver: no feasible 1 cm move of the body in any
  // direction lowers the worst phase's peak by more than 1e-3.
  int worst = 0;
  for (int k = 1; k < 6; ++k)
    if (r.sway[k].peak_saturation > r.sway[worst].peak_saturation) worst = k;
  const Eigen::Vector3d d = r.sway[worst].displacement;
  for (int a = 0; a < 3; ++a)
    for (double s : {-0.01, 0.01}) {
      Eigen::Vector3d dp = d;
      dp[a] += s;
      if (std::abs(dp.x()) > o.max_shift_xy || std::abs(dp.y()) > o.max_shift_xy ||
          dp.z() > o.max_shift_up || -dp.z() > o.max_shift_down)
        continue;
      const GaitPhase p = evaluate_gait_phase(m, o, worst, dp);
      if (!p.reachable || p.support_margin < o.min_support_margin) continue;
      EXPECT_GT(p.peak_saturation, r.sway[worst].peak_saturation - 1e-3) << "axis " << a << " step " << s;
    }
}
