// The walker in ODE: the model built right (ODE's bodies agree with cpp/walker's kinematics),
// joint position control, the compliant wheel contacts against the closed form and the sag model
// (seed 003 §5.1.1), and §4.1's Moses Lake lesson — the sag-compensated swing clears a rock that
// the rigid plan hits.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "ernest/walker_sim/sag_compensation.hpp"
#include "test_util.hpp"

using namespace ernest::walker_sim;
using ernest::testing::invalid_argument_message;
using ernest::walker::WalkerModel;

namespace {
const WalkerModel& sdm_b() {
  static const WalkerModel m(ernest::walker::sdm_b_parameters());
  return m;
}
}  // namespace

TEST(WalkerSim, StandsOnSixSpringsAndTracksJointTargetsConsistentlyWithTheModel) {
  const WalkerModel& m = sdm_b();
  const Eigen::MatrixXd q0 = m.standard_configuration();
  WalkerSim sim(m, m.standard_body_pose(), q0);
  sim.hold(q0, 1.5);
  // Closed form: six equal springs under a CG on the axis carry m g / 6 each and the chassis
  // sinks by m g / (6 k) without tilting.
  const double weight = m.params().total_mass() * m.params().gravity, k = sim.options().contact_stiffness;
  const Eigen::VectorXd loads = sim.wheel_loads();
  for (int leg = 0; leg < 6; ++leg) EXPECT_NEAR(loads[leg], weight / 6.0, 1e-3 * weight) << leg;
  const Eigen::Isometry3d body = sim.body_pose();
  EXPECT_NEAR(m.params().standard_height - body.translation().z(), weight / (6.0 * k), 2e-4);
  EXPECT_LT(Eigen::AngleAxisd(body.linear()).angle(), 1e-4);
  EXPECT_LT((sim.joint_angles() - q0).cwiseAbs().maxCoeff(), 2e-3);
  // Raise leg 0 by moving its hip pitch: the joint follows the target, and the wheel that ODE
  // carries is where the model's forward kinematics puts it for the measured angles and pose.
  Eigen::MatrixXd q1 = q0;
  q1(1, 0) -= 0.25;
  for (int s = 0; s < 200; ++s) sim.step(q1);
  EXPECT_LT((sim.joint_angles() - q1).cwiseAbs().maxCoeff(), 2e-3);
  const Eigen::Isometry3d foot = sim.body_pose() * m.foot_pose(0, sim.joint_angles().col(0));
  EXPECT_LT((sim.wheel_centres().col(0) - foot.translation()).norm(), 1e-4);
  EXPECT_LT((sim.wheel_axles().col(0) - foot.linear().col(1)).norm(), 1e-4);
  EXPECT_GT(sim.ground_clearance(0), 0.05);
  EXPECT_EQ(sim.wheel_loads()[0], 0.0);
  EXPECT_NEAR(sim.wheel_loads().sum(), weight, 2e-3 * weight);
  EXPECT_TRUE(std::isinf(sim.rock_clearance(0)));  // no rocks
}

TEST(WalkerSim, WheelRockClearanceMatchesTheClosedForm) {
  // Upright wheel (axle along y) of radius 0.35 m with its centre 0.5 m up, a box below it.
  Rock r;
  r.centre = Eigen::Vector3d(0.0, 0.0, 0.05);
  r.half_extents = Eigen::Vector3d(0.3, 0.3, 0.05);
  const Eigen::Vector3d c(0.0, 0.0, 0.5), axle = Eigen::Vector3d::UnitY();
  EXPECT_NEAR(wheel_rock_clearance(c, axle, 0.35, 0.25, r), 0.5 - 0.35 - 0.1, 1e-4);
  r.centre.z() = 0.15;  // top at 0.2 m: 5 cm into the rim
  EXPECT_NEAR(wheel_rock_clearance(c, axle, 0.35, 0.25, r), -0.05, 2e-3);
  EXPECT_NEAR(wheel_ground_clearance(c, axle, 0.35), 0.15, 1e-12);
  r.half_extents.y() = -0.1;
  EXPECT_NE(invalid_argument_message([&] { r.validate(); }).find("half_extents"), std::string::npos);
  EXPECT_NE(invalid_argument_message([&] { wheel_rock_clearance(c, axle, 0.35, 0.25, r); })
                .find("half_extents"), std::string::npos);
  r.half_extents.y() = 0.3;
  // FCL would assert (abort) on these: each is refused with the argument's name
  const double nan = std::nan("");
  EXPECT_NE(invalid_argument_message([&] { wheel_rock_clearance(c, axle, 0.35, nan, r); })
                .find("width"), std::string::npos);
  EXPECT_NE(invalid_argument_message([&] { wheel_rock_clearance(c, axle, nan, 0.25, r); })
                .find("radius"), std::string::npos);
  EXPECT_NE(invalid_argument_message([&] { wheel_rock_clearance(Eigen::Vector3d(nan, 0, 0), axle, 0.35, 0.25, r); })
                .find("centre"), std::string::npos);
  EXPECT_NE(invalid_argument_message([&] { wheel_rock_clearance(c, Eigen::Vector3d(0, nan, 0), 0.35, 0.25, r); })
                .find("axle"), std::string::npos);
  EXPECT_NE(invalid_argument_message([&] { wheel_rock_clearance(c, Eigen::Vector3d::Zero(), 0.35, 0.25, r); })
                .find("axle"), std::string::npos);
  r.centre.x() = nan;
  EXPECT_NE(invalid_argument_message([&] { wheel_rock_clearance(c, axle, 0.35, 0.25, r); })
                .find("centre"), std::string::npos);
}

TEST(WalkerSim, SagCompensatedSwingClearsTheRockTheRigidPlanHits) {
  const WalkerModel& m = sdm_b();
  const SagScenarioOptions o;
  const SagScenarioResult r = run_sag_scenario(m, o);
  // Both plans keep the requested 3 cm on paper (the lift search stops just above it) ...
  for (const SwingPlan* p : {&r.rigid, &r.compensated}) {
    EXPECT_GE(p->planned_clearance, o.planned_clearance);
    EXPECT_LT(p->planned_clearance, o.planned_clearance + 0.01);
    EXPECT_GT(p->lift_height, o.min_lift);
  }
  // ... but executed on the compliant robot the rigid one hits the rock (the chassis sags about
  // 4 cm at the lifted corner), while the compensated one keeps its clearance to within 5 mm.
  EXPECT_LT(r.rigid_run.min_rock_clearance, 0.0);
  EXPECT_GT(r.compensated_run.min_rock_clearance, 0.0);
  EXPECT_NEAR(r.compensated_run.min_rock_clearance, r.compensated.planned_clearance, 0.005);
  EXPECT_GT(r.compensated.lift_height, r.rigid.lift_height + 0.02);
  EXPECT_GT(r.rigid_run.min_ground_clearance, 0.1);  // the wheel was in the air over the transfer
  EXPECT_GT(r.compensated_run.min_ground_clearance, 0.1);
  // The simulator's sag against the sag model (an independent check of both: ODE's soft contacts
  // and articulated legs vs LM over eqs 4–12). Closed form for six wheels: m g / (6 k).
  const double weight = m.params().total_mass() * m.params().gravity;
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(r.rigid_corners[k] - r.predicted_six_corners[k], weight / (6 * o.sim.contact_stiffness), 1e-6);
  }
  EXPECT_LT(r.six_error, 5e-4);
  EXPECT_LT(r.lifted_error, 1e-3);
  // With leg 0 in the air its corner sinks most and the opposite one least (Fig. 11b's pattern).
  Eigen::Index lowest, highest;
  r.measured_lifted_corners.minCoeff(&lowest);
  r.measured_lifted_corners.maxCoeff(&highest);
  EXPECT_EQ(lowest, 0);
  EXPECT_EQ(highest, 3);
  EXPECT_GT(r.rigid_corners[0] - r.measured_lifted_corners[0], 0.03);
  std::printf("rigid: lift %.3f m, on paper %.4f m, executed %.4f m; compensated: lift %.3f m, on paper %.4f m, "
              "executed %.4f m; sag error six %.5f m, lifted %.5f m\n",
              r.rigid.lift_height, r.rigid.planned_clearance, r.rigid_run.min_rock_clearance,
              r.compensated.lift_height, r.compensated.planned_clearance, r.compensated_run.min_rock_clearance,
              r.six_error, r.lifted_error);
}

TEST(WalkerSim, RunawayRaisesAndInvalidInputNamesTheField) {
  const WalkerModel& m = sdm_b();
  const Eigen::MatrixXd q0 = m.standard_configuration();
  WalkerSimOptions o;
  o.dt = 0.0;
  EXPECT_NE(invalid_argument_message([&] { WalkerSim(m, m.standard_body_pose(), q0, {}, o); }).find("dt"),
            std::string::npos);
  o = WalkerSimOptions{};
  o.contact_stiffness = std::nan("");
  EXPECT_NE(invalid_argument_message([&] { o.validate(); }).find("contact_stiffness"), std::string::npos);
  WalkerSim sim(m, m.standard_body_pose(), q0);
  Eigen::MatrixXd bad = q0;
  bad(0, 0) = std::nan("");
  EXPECT_THROW(sim.step(bad), std::invalid_argument);
  EXPECT_THROW(sim.step(q0, Eigen::MatrixXd::Constant(q0.rows(), q0.cols(), INFINITY)), std::invalid_argument);
  // A rock spawned 35 cm into a wheel, infinitely stiff and undamped (ERP = 1): ODE pushes it out
  // within one step, at 70 m/s — detected as a runaway and raised; the simulator then refuses to go on.
  o = WalkerSimOptions{};
  o.rock_stiffness = 1e10;
  o.rock_damping = 0.0;
  Rock rock;
  rock.centre = sim.wheel_centres().col(0) + Eigen::Vector3d(0.4, 0.0, 0.0);
  rock.half_extents = Eigen::Vector3d::Constant(0.4);
  WalkerSim wild(m, m.standard_body_pose(), q0, {rock}, o);
  EXPECT_THROW(wild.step(q0), WalkerSimDiverged);
  EXPECT_THROW(wild.step(q0), WalkerSimDiverged);
}
