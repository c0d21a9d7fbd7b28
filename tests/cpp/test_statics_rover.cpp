// Tests of cpp/statics' ERNEST part: the mass model and its fit (seed 004 §3.2, eq 11) and the
// lift-off roll torque LP (Fig. 25), against closed forms and the simulator itself.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <memory>
#include <random>
#include <string>

#include "ernest/dynamics/rover_sim.hpp"
#include "ernest/statics/liftoff.hpp"
#include "ernest/statics/load_survey.hpp"
#include "ernest/statics/mass_model.hpp"

using namespace ernest::statics;
namespace dyn = ernest::dynamics;

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kG = 9.81;

// Flat ground, psi = phi = 0: the §3.2 model in closed form from geometry and masses only. The free
// (or torqued) roll joint splits the front pair; pitch balance gives front vs rear; the chassis
// carries the reaction of the roll torque to the rear pair.
Eigen::Vector4d flat_closed_form(const MassModel& m, const RoverGeometry& g, double tau) {
  const double w = (m.chassis_mass + m.bogie_mass) * g.gravity, l = g.wheelbase;
  const double xc = (m.chassis_mass * m.chassis_com.x() + m.bogie_mass * 0.5 * l) /
                    (m.chassis_mass + m.bogie_mass);
  const double yc = m.chassis_mass * m.chassis_com.y() / (m.chassis_mass + m.bogie_mass);
  const double rear = w * (0.5 - xc / l), front = w - rear;
  const double half = 0.5 * g.track;
  // front: (t/2)(FL - FR) + tau = 0; all: (t/2)(FL - FR + RL - RR) = w yc
  const double dfront = -tau / half, drear = w * yc / half - dfront;
  return {0.5 * (front + dfront), 0.5 * (front - dfront), 0.5 * (rear + drear),
          0.5 * (rear - drear)};
}

const std::vector<LoadPose>& default_survey() {
  static const std::vector<LoadPose> poses = survey_loads(dyn::RoverParameters{});
  return poses;
}

}  // namespace

TEST(MassModel, FromParametersGroupsBodiesAsSection32) {
  const dyn::RoverParameters p;
  const MassModel m = MassModel::from_parameters(p);
  EXPECT_NEAR(m.chassis_mass + m.bogie_mass, p.total_mass(), 1e-12);
  EXPECT_NEAR(m.bogie_mass, 12.0 + 2 * 3.0, 1e-12);
  EXPECT_NEAR(m.chassis_com.x(), (51.0 * -0.12 + 6.0 * -0.43) / 57.0, 1e-12);
  EXPECT_NEAR(m.chassis_com.z(), 51.0 * 0.33 / 57.0, 1e-12);
  EXPECT_NEAR(m.bogie_com_height, 12.0 * 0.10 / 18.0, 1e-12);
}

TEST(MassModel, FlatGroundMatchesClosedFormWithAndWithoutRollTorque) {
  MassModel m = MassModel::from_parameters(dyn::RoverParameters{});
  m.chassis_com.y() = 0.02;  // an asymmetric chassis so that the rear split is tested too
  const RoverGeometry g;
  for (double tau : {0.0, 35.0, -60.0}) {
    LoadPose pose;
    pose.roll_torque = tau;
    const Eigen::Vector4d f = predict_loads(m, g, pose);
    const Eigen::Vector4d ref = flat_closed_form(m, g, tau);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(f[i], ref[i], 1e-9) << "tau " << tau << " wheel " << i;
  }
}

TEST(MassModel, MirrorSymmetryAndEquilibriumOnASlope) {
  const MassModel m = MassModel::from_parameters(dyn::RoverParameters{});  // y_c = 0
  const RoverGeometry g;
  for (double psi : {10.0 * kDeg, 35.0 * kDeg}) {
    // heading h and gimbal psi mirror into -h, -psi: the left and right loads swap
    LoadPose a = slope_pose(20 * kDeg, 30 * kDeg, psi), b = slope_pose(20 * kDeg, -30 * kDeg, -psi);
    const Eigen::Vector4d fa = predict_loads(m, g, a), fb = predict_loads(m, g, b);
    EXPECT_NEAR(fa[0], fb[1], 1e-9);
    EXPECT_NEAR(fa[1], fb[0], 1e-9);
    EXPECT_NEAR(fa[2], fb[3], 1e-9);
    EXPECT_NEAR(fa[3], fb[2], 1e-9);
    EXPECT_NEAR(fa.sum(), 75.0 * kG, 1e-9);
  }
  // Uphill, psi = 0: the downhill (rear) pair carries more, by the height of the CoM.
  const Eigen::Vector4d up = predict_loads(m, g, slope_pose(20 * kDeg, 0.0, 0.0));
  const Eigen::Vector4d flat = predict_loads(m, g, slope_pose(0.0, 0.0, 0.0));
  EXPECT_GT(up[2] / up.sum(), flat[2] / flat.sum() + 0.05);
}

TEST(MassFit, RecoversTheSimulatorsMassModelFromNoiseFreeSurvey) {
  const dyn::RoverParameters p;
  const MassModel truth = MassModel::from_parameters(p);
  const auto& poses = default_survey();
  ASSERT_GE(poses.size(), 40u);
  // the survey varies the chassis attitude and the bogie roll, not only the yaw
  double max_roll = 0.0, max_pitch = 0.0, max_phi = 0.0;
  for (const auto& q : poses) {
    const Eigen::Matrix3d r =
        Eigen::Quaterniond(q.chassis_quaternion[0], q.chassis_quaternion[1],
                           q.chassis_quaternion[2], q.chassis_quaternion[3]).toRotationMatrix();
    max_pitch = std::max(max_pitch, std::abs(std::asin(r(2, 0))));
    max_roll = std::max(max_roll, std::abs(std::atan2(r(2, 1), r(2, 2))));
    max_phi = std::max(max_phi, std::abs(q.phi));
  }
  EXPECT_GT(max_pitch, 15 * kDeg);
  EXPECT_GT(max_roll, 15 * kDeg);
  EXPECT_GT(max_phi, 3 * kDeg);
  MassModel guess;  // a rough guess, not the truth
  guess.chassis_mass = 40.0;
  guess.bogie_mass = 30.0;
  guess.chassis_com = {0.0, 0.05, 0.5};
  guess.bogie_com_height = 0.2;
  const RoverGeometry geo = RoverGeometry::from_parameters(p);
  // All six free: the bogie/chassis split is not identifiable (see the next test), but the
  // whole-rover quantities are: total mass, whole CoM and the bogie's moment about the roll axis.
  {
    const MassFitResult r = fit_mass_model(poses, geo, guess);
    ASSERT_TRUE(r.converged) << r.status;
    EXPECT_EQ(r.rank, 5);
    EXPECT_FALSE(r.identifiable[0]);
    EXPECT_TRUE(std::isinf(r.std_error[1]));
    EXPECT_GT(r.r_squared, 0.99);
    auto whole = [&](const MassModel& m) {
      const double mt = m.chassis_mass + m.bogie_mass;
      const Eigen::Vector3d gimbal(0.5 * p.wheelbase, 0.0, p.gimbal_height);
      const Eigen::Vector3d bogie(gimbal.x(), 0.0, m.bogie_com_height);
      const Eigen::Vector3d com = (m.chassis_mass * m.chassis_com + m.bogie_mass * bogie) / mt;
      return Eigen::Vector4d(mt, com.x(), com.z(), m.bogie_mass * (m.bogie_com_height - gimbal.z()));
    };
    const Eigen::Vector4d wt = whole(truth), we = whole(r.model);
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(we[k], wt[k], 0.02 * std::abs(wt[k])) << k;
  }
  // Bogie mass weighed on its own (fixed): the five others within 2 %.
  MassFitOptions o;
  o.fixed[1] = true;
  guess.bogie_mass = truth.bogie_mass;
  const MassFitResult r = fit_mass_model(poses, geo, guess, o);
  ASSERT_TRUE(r.converged) << r.status;
  EXPECT_EQ(r.rank, 5);
  const auto t = truth.vector(), e = r.model.vector();
  for (int k : {0, 2, 4, 5})
    EXPECT_NEAR(e[k], t[k], 0.02 * std::abs(t[k])) << mass_model_parameter_names()[k];
  EXPECT_NEAR(e[3], t[3], 0.02 * 0.5 * p.track);  // y_c = 0: 2 % of the half track
  EXPECT_GT(r.r_squared, 0.99);
  EXPECT_EQ(r.std_error[1], 0.0);
  for (int k = 0; k < 6; ++k) EXPECT_TRUE(std::isfinite(r.std_error[k]) && r.identifiable[k]);
}

TEST(MassModel, MassMovedBetweenBogieAndChassisAtTheGimbalChangesNoLoad) {
  // Why eq 11 identifies only five parameters on this rover: the gimbal point lies on the bogie's
  // CoM line, so delta kg moved from the bogie to the chassis at that point leaves every load of
  // every pose (and every roll-axis moment) unchanged.
  const dyn::RoverParameters p;
  const RoverGeometry g = RoverGeometry::from_parameters(p);
  const MassModel a = MassModel::from_parameters(p);
  const double d = 5.0;
  const Eigen::Vector3d gimbal(0.5 * p.wheelbase, 0.0, p.gimbal_height);
  MassModel b = a;
  b.chassis_mass += d;
  b.chassis_com = (a.chassis_mass * a.chassis_com + d * gimbal) / b.chassis_mass;
  b.bogie_mass -= d;
  b.bogie_com_height = p.gimbal_height +
                       a.bogie_mass * (a.bogie_com_height - p.gimbal_height) / b.bogie_mass;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 20; ++k) {
    LoadPose pose = slope_pose(25 * kDeg * u(rng), M_PI * u(rng), 40 * kDeg * u(rng));
    pose.phi = 10 * kDeg * u(rng);
    pose.roll_torque = 30 * u(rng);
    const Eigen::Vector4d fa = predict_loads(a, g, pose), fb = predict_loads(b, g, pose);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(fa[i], fb[i], 1e-9) << k;
  }
}

TEST(MassFit, ReportedUncertaintyMatchesTheScatterOverNoiseSeeds) {
  const dyn::RoverParameters p;
  const RoverGeometry geo = RoverGeometry::from_parameters(p);
  const MassModel truth = MassModel::from_parameters(p);
  const auto& clean = default_survey();
  MassFitOptions o;
  o.fixed[1] = true;  // bogie mass known (see MassMovedBetweenBogieAndChassisAtTheGimbal...)
  const MassFitResult ref = fit_mass_model(clean, geo, truth, o);
  const double sigma = 10.0;  // [N] sensor noise on each load
  const int seeds = 20;
  Eigen::Matrix<double, 6, 1> z2 = Eigen::Matrix<double, 6, 1>::Zero();
  for (int s = 0; s < seeds; ++s) {
    std::mt19937_64 rng(1000 + s);
    std::normal_distribution<double> noise(0.0, sigma);
    std::vector<LoadPose> noisy = clean;
    for (auto& q : noisy)
      for (int i = 0; i < 4; ++i) q.loads[i] += noise(rng);
    const MassFitResult r = fit_mass_model(noisy, geo, truth, o);
    ASSERT_TRUE(r.converged) << r.status;
    EXPECT_NEAR(r.residual_sigma, std::hypot(sigma, ref.residual_sigma), 0.2 * sigma);
    for (int k : {0, 2, 3, 4, 5}) {
      const double z = (r.model.vector()[k] - ref.model.vector()[k]) / r.std_error[k];
      EXPECT_LT(std::abs(z), 3.5) << mass_model_parameter_names()[k] << " seed " << s;
      z2[k] += z * z / seeds;
      // the simulator's own value lies within 3.5 sigma too (its model error is below the noise)
      const double zt = (r.model.vector()[k] - truth.vector()[k]) / r.std_error[k];
      EXPECT_LT(std::abs(zt), 3.5) << mass_model_parameter_names()[k] << " seed " << s;
    }
  }
  // root-mean-square z over the seeds ~ 1 when the reported sigma is right (20 seeds: +-35 %)
  for (int k : {0, 2, 3, 4, 5}) {
    EXPECT_GT(std::sqrt(z2[k]), 0.55) << mass_model_parameter_names()[k];
    EXPECT_LT(std::sqrt(z2[k]), 1.5) << mass_model_parameter_names()[k];
  }
}

TEST(MassFit, FlatGroundAloneCannotIdentifyTheHeights) {
  std::vector<LoadPose> flat;
  const MassModel truth = MassModel::from_parameters(dyn::RoverParameters{});
  const RoverGeometry g;
  for (double psi : {-40.0, -20.0, 0.0, 20.0, 40.0}) {
    LoadPose q = slope_pose(0.0, 0.0, psi * kDeg);
    q.loads = predict_loads(truth, g, q);
    flat.push_back(q);
  }
  const MassFitResult r = fit_mass_model(flat, g);
  EXPECT_EQ(r.rank, 3);  // total mass, and the whole CoM's x and y
  EXPECT_TRUE(std::isinf(r.std_error[4]));  // z_c
  EXPECT_TRUE(std::isinf(r.std_error[5]));  // z_b
  EXPECT_NEAR(r.model.chassis_mass + r.model.bogie_mass, 75.0, 1e-6);
  EXPECT_NEAR(r.model.chassis_com.y(), truth.chassis_com.y(), 1e-8);
}

TEST(MassFit, BadInputNamesTheField) {
  std::vector<LoadPose> poses(3);
  poses[1].loads[2] = std::nan("");
  try {
    fit_mass_model(poses, RoverGeometry{});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("poses[1].loads"), std::string::npos) << e.what();
  }
  EXPECT_THROW(fit_mass_model(std::vector<LoadPose>(1), RoverGeometry{}), std::invalid_argument);
  MassModel bad;
  bad.bogie_mass = -1.0;
  EXPECT_THROW(predict_loads(bad, RoverGeometry{}, LoadPose{}), std::invalid_argument);
  LoadPose nan_pose;
  nan_pose.psi = std::nan("");
  EXPECT_THROW(predict_loads(MassModel{}, RoverGeometry{}, nan_pose), std::invalid_argument);
  LiftoffOptions lo;
  lo.torque_limit = -3.0;
  EXPECT_THROW(max_roll_torque(MassModel{}, RoverGeometry{}, LoadPose{}, lo), std::invalid_argument);
}

TEST(Liftoff, SymmetricFlatCaseInClosedForm) {
  const MassModel m = MassModel::from_parameters(dyn::RoverParameters{});
  const RoverGeometry g;
  const LiftoffResult r = max_roll_torque(m, g, slope_pose(0.0, 0.0, 0.0));
  ASSERT_TRUE(r.feasible);
  // tau > 0 unloads FL and RR (flat_closed_form): the lighter pair's wheel lifts first at
  // tau = (t/2) min(front pair, rear pair); symmetric in sign.
  const Eigen::Vector4d f0 = flat_closed_form(m, g, 0.0);
  const double front = f0[0] + f0[1], rear = f0[2] + f0[3];
  const double expect = 0.5 * g.track * std::min(front, rear);
  EXPECT_NEAR(r.positive.torque, expect, 1e-6);
  EXPECT_NEAR(r.negative.torque, -expect, 1e-6);
  EXPECT_EQ(r.positive.lifted_wheel, front < rear ? 0 : 3);
  EXPECT_EQ(r.negative.lifted_wheel, front < rear ? 1 : 2);
  EXPECT_NEAR(r.positive.loads[r.positive.lifted_wheel], 0.0, 1e-6);
  EXPECT_NEAR(r.positive.loads.sum(), 75.0 * kG, 1e-6);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(r.loads_at_zero[i], f0[i], 1e-9);
  // an actuator bound below the lift-off torque binds instead
  LiftoffOptions o;
  o.torque_limit = 50.0;
  const LiftoffResult b = max_roll_torque(m, g, slope_pose(0.0, 0.0, 0.0), o);
  EXPECT_NEAR(b.positive.torque, 50.0, 1e-9);
  EXPECT_TRUE(b.positive.torque_limited);
  EXPECT_EQ(b.positive.lifted_wheel, -1);
}

TEST(Liftoff, LpAgreesWithTheRatioTestOnTheAffineLoads) {
  // Independent of GLPK: the loads are affine in tau, f = A^-1 (b + t tau); the limit is the
  // first load to reach min_load.
  const MassModel m = MassModel::from_parameters(dyn::RoverParameters{});
  const RoverGeometry g;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  for (int k = 0; k < 60; ++k) {
    LoadPose pose = slope_pose(20 * kDeg * std::abs(u(rng)), M_PI * u(rng), 45 * kDeg * u(rng));
    pose.phi = 5 * kDeg * u(rng);
    LiftoffOptions o;
    o.min_load = 10.0;
    const LiftoffResult r = max_roll_torque(m, g, pose, o);
    const LoadEquations e = load_equations(m, g, pose);
    const Eigen::Vector4d f0 = e.A.fullPivLu().solve(e.b), s = e.A.fullPivLu().solve(e.t);
    double hi = ernest::kInf, lo = -ernest::kInf;
    for (int i = 0; i < 4; ++i) {
      const double tau_i = (o.min_load - f0[i]) / s[i];  // where load i reaches min_load
      if (s[i] < 0) hi = std::min(hi, tau_i);
      if (s[i] > 0) lo = std::max(lo, tau_i);
    }
    const bool feasible = lo <= hi;
    ASSERT_EQ(r.feasible, feasible) << k;
    if (!feasible) continue;
    ++checked;
    EXPECT_NEAR(r.positive.torque, hi, 1e-6 * (1 + std::abs(hi))) << k;
    EXPECT_NEAR(r.negative.torque, lo, 1e-6 * (1 + std::abs(lo))) << k;
    const Eigen::Vector4d fh = f0 + s * hi;
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(r.positive.loads[i], fh[i], 1e-6) << k;
  }
  EXPECT_GT(checked, 40);
}

namespace {

// Simulator check: settle at psi on rigid ground with the clutch engaged, then apply a constant
// roll torque (Torque mode, ramped in 2 s, held 3 s); the smallest wheel load over the last second
// and the final bogie roll.
struct TorqueRun {
  double min_load;
  double final_phi;
};

std::unique_ptr<dyn::RoverSim> settled(const dyn::RoverParameters& p, const dyn::HeightMap& ground,
                                       double psi) {
  dyn::SimOptions so;
  so.ground = dyn::GroundType::Rigid;
  so.friction = 0.8;
  auto sim = std::make_unique<dyn::RoverSim>(p, ground, std::vector<dyn::BoxObstacle>{}, so);
  sim->reset(0.0, 0.0, 0.0, psi, 0.0);
  dyn::Commands c;  // gimbal on: yaw held at zero rate
  c.clutch_engage = true;
  sim->set_commands(c);
  sim->step_n(80);
  EXPECT_EQ(sim->state().clutch, dyn::ClutchState::Engaged);
  return sim;
}

TorqueRun run_roll_torque(dyn::RoverSim& sim, double tau) {
  dyn::Commands c = sim.commands();
  c.roll_mode = dyn::ActuatorMode::Torque;
  const int ramp = 80, hold = 120;
  TorqueRun out{1e9, 0.0};
  for (int k = 0; k < ramp + hold; ++k) {
    c.roll_torque = tau * std::min(1.0, (k + 1.0) / ramp);
    sim.set_commands(c);
    sim.step();
    if (k >= ramp + hold - 40)
      for (double l : sim.state().wheel_load) out.min_load = std::min(out.min_load, l);
  }
  out.final_phi = sim.state().gimbal_roll;
  return out;
}

}  // namespace

TEST(Liftoff, SimulatorLiftsAWheelJustAboveTheLimitOnly) {
  dyn::RoverParameters p;
  p.gimbal_motor.current_limit = 25.0;  // a stronger roll drive, so that it can reach every limit
  const MassModel m = MassModel::from_parameters(p);
  const RoverGeometry g = RoverGeometry::from_parameters(p);
  LiftoffOptions o;
  o.torque_limit = p.gimbal_motor.max_output_torque();
  struct Case {
    double slope_deg, psi_deg;
  };
  for (const Case k : {Case{0.0, 0.0}, Case{0.0, 35.0}, Case{20.0, 0.0}, Case{20.0, 35.0}}) {
    const double slope = k.slope_deg * kDeg, psi = k.psi_deg * kDeg;
    const dyn::HeightMap ground = slope == 0.0 ? dyn::HeightMap::flat(10, 10, 0.25, 0.0)
                                               : dyn::HeightMap::slope(slope, 10, 10, 0.25, -5, -5);
    auto sim = settled(p, ground, psi);
    const Eigen::Vector3d n(-std::sin(slope), 0.0, std::cos(slope));
    // The LP on the settled configuration: as the mass model has it (vertical forces only, Fig.
    // 25) and with the tyres' horizontal forces the FTS measure at zero torque.
    LoadPose pose = pose_from_state(p, sim->state(), kG, n);
    const LiftoffResult rh = max_roll_torque(m, g, pose, o);
    pose.horizontal_forces.setZero();
    const LiftoffResult r0 = max_roll_torque(m, g, pose, o);
    ASSERT_TRUE(r0.feasible && rh.feasible);
    const dyn::Snapshot snap = sim->snapshot();
    for (int dir : {+1, -1}) {
      const double t0 = dir > 0 ? r0.positive.torque : r0.negative.torque;
      const double th = dir > 0 ? rh.positive.torque : rh.negative.torque;
      ASSERT_LT(std::max(std::abs(t0), std::abs(th)) * 1.1, o.torque_limit);
      // Level ground or a bogie in line with the slope: the tyres carry no share of the weight
      // sideways and both LPs agree with the simulator within 10 %. A bogie yawed on the slope:
      // its tyres' side forces carry some of the weight across the roll axis and change as it
      // rolls, which rigid statics cannot know; the two LPs bracket the simulator's limit.
      const bool side_loaded = slope != 0.0 && psi != 0.0;
      const double lo = side_loaded ? std::min(std::abs(t0), std::abs(th)) : std::abs(t0);
      const double hi = side_loaded ? std::max(std::abs(t0), std::abs(th)) : std::abs(t0);
      if (!side_loaded) EXPECT_NEAR(th, t0, 0.03 * std::abs(t0));
      sim->restore(snap);
      const TorqueRun below = run_roll_torque(*sim, dir * 0.9 * lo);
      sim->restore(snap);
      const TorqueRun above = run_roll_torque(*sim, dir * 1.1 * hi);
      const std::string what = "slope " + std::to_string(k.slope_deg) + " psi " +
                               std::to_string(k.psi_deg) + " limits " + std::to_string(t0) +
                               " " + std::to_string(th);
      EXPECT_GT(below.min_load, 3.0) << what;
      EXPECT_LT(above.min_load, 1e-6) << what;
      EXPECT_GT(std::abs(above.final_phi), std::abs(below.final_phi) + 1 * kDeg) << what;
    }
  }
}
