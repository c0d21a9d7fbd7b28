// Tests of the episode core RoverEnv (seed 004 §4.2–4.5) on the ODE simulator.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "ernest/envs/rover_env.hpp"

using namespace ernest;
using envs::EnvOptions;
using envs::RoverEnv;
using sensing::ActionVector;

namespace {
EnvOptions flat_rigid() {
  EnvOptions o;
  o.scenario.kind = envs::ScenarioKind::Flat;
  o.rigid_ground = true;
  return o;
}
const ActionVector kStop(-1.0, 0.0, 0.0);      // V_x = 0
const ActionVector kSlow(0.0, 0.0, 0.0);       // V_x = 0.1 m/s
}  // namespace

TEST(RoverEnv, FlatHardGroundAtRestSeesNothing) {
  RoverEnv env(dynamics::RoverParameters{}, flat_rigid());
  env.reset(0);
  envs::StepResult r;
  for (int i = 0; i < 8; ++i) r = env.step(kStop);  // 4 s: the 0.5 Hz filter has settled
  const auto& st = env.sim().state();
  EXPECT_LT(std::abs(st.roll), 1e-3);
  EXPECT_LT(std::abs(st.pitch), 2e-3);
  EXPECT_LT(env.elevation().values.cwiseAbs().maxCoeff(), 2e-3);  // wheel-high frame, flat map
  // Processed force–torque values: the four-sensor mean removed, what is left on flat ground at
  // rest is each wheel's load minus the mean load (the CoM is not centred), nothing lateral.
  const double mean_load =
      (st.wheel_load[0] + st.wheel_load[1] + st.wheel_load[2] + st.wheel_load[3]) / 4;
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(env.fts()(i, 2), st.wheel_load[i] - mean_load, 1.0) << "wheel " << i;
    EXPECT_LT(std::abs(env.fts()(i, 1)), 1.0);
    EXPECT_LT(std::abs(env.fts()(i, 3)), 1.0);
  }
  // left/right symmetric
  EXPECT_NEAR(env.fts()(0, 2), env.fts()(1, 2), 0.5);
  EXPECT_NEAR(env.fts()(2, 2), env.fts()(3, 2), 0.5);
  EXPECT_NEAR(r.observation[sensing::kRoll], 0.0, 1e-2);
  EXPECT_NEAR(r.observation[sensing::kLateralDeviation], 0.0, 1e-3);
  EXPECT_FALSE(r.terminated || r.truncated);
}

TEST(RoverEnv, RoverAtRestOnSoilStaysStill) {
  // With the environments' eps_motion (0.01 m/s) the rest/moving stress shapes of eq 16 do not
  // flip on the wheel synchroniser's small corrections: at rest on M90 the loads are steady (Table
  // 2's 5e-5 gives a stick–slip cycle with ~15 N load std).
  EnvOptions o;
  o.scenario.kind = envs::ScenarioKind::Flat;
  RoverEnv env(dynamics::RoverParameters{}, o);
  env.reset(0);
  for (int i = 0; i < 6; ++i) env.step(kStop);
  double lo = 1e9, hi = -1e9;
  for (int i = 0; i < 4; ++i) {
    env.step(kStop);
    lo = std::min(lo, env.sim().state().wheel_load[0]);
    hi = std::max(hi, env.sim().state().wheel_load[0]);
  }
  EXPECT_LT(hi - lo, 1.0);
  EXPECT_GT(lo, 150.0);
  EXPECT_LT(std::abs(env.sim().state().linear_velocity.x()), 1e-3);
}

TEST(RoverEnv, DrivingStraightGivesFiveCentimetresPerStep) {
  // 0.1 m/s for one 0.5 s policy step: 0.05 m of progress and reward w_s 0.05 / 0.5 = 0.2.
  RoverEnv env(dynamics::RoverParameters{}, flat_rigid());
  env.reset(1);
  env.step(kSlow);  // accelerate
  for (int i = 0; i < 10; ++i) {
    const envs::StepResult r = env.step(kSlow);
    EXPECT_NEAR(r.reward.progress, 0.05, 2e-3);
    EXPECT_NEAR(r.reward.reward, 2.0 * r.reward.progress / 0.5 + r.reward.lateral_term +
                                     r.reward.torque_term, 1e-12);
    EXPECT_NEAR(r.reward.reward, 0.2, 1e-2);
    EXPECT_NEAR(r.reward.lateral, 0.0, 1e-3);
  }
  EXPECT_NEAR(env.metrics().travel_reduction(), 0.0, 0.05);
}

TEST(RoverEnv, SameSeedSameEpisode) {
  EnvOptions o;
  o.scenario.kind = envs::ScenarioKind::RockField;
  RoverEnv a(dynamics::RoverParameters{}, o), b(dynamics::RoverParameters{}, o);
  EXPECT_EQ(a.reset(7), b.reset(7));
  for (int i = 0; i < 6; ++i) {
    const ActionVector act(std::sin(i), std::cos(i), 0.5 * std::sin(2 * i));
    const envs::StepResult ra = a.step(act), rb = b.step(act);
    ASSERT_EQ(ra.observation, rb.observation) << "step " << i;
    ASSERT_EQ(ra.reward.reward, rb.reward.reward);
  }
  RoverEnv c(dynamics::RoverParameters{}, o);
  EXPECT_NE(c.reset(8), a.reset(7));
}

TEST(RoverEnv, EpisodeEndsAtTheMapEndOrTheTimeLimit) {
  EnvOptions o = flat_rigid();
  RoverEnv env(dynamics::RoverParameters{}, o);
  env.reset(2);
  envs::StepResult r;
  int steps = 0;
  do {
    r = env.step(ActionVector(1.0, 0.0, 0.0));  // 0.2 m/s
    ++steps;
  } while (!r.terminated && !r.truncated && steps < 1000);
  EXPECT_TRUE(r.terminated);
  EXPECT_EQ(r.message, "reached the end of the map");
  EXPECT_GE(env.scenario().path.arc_length(env.sim().state().position.x(), 0.0),
            env.scenario().end_distance);
  EXPECT_THROW(env.step(kStop), std::logic_error);

  o.episode_duration = 3.0;
  RoverEnv short_env(dynamics::RoverParameters{}, o);
  short_env.reset(2);
  for (int i = 0; i < 5; ++i) EXPECT_FALSE(short_env.step(kStop).truncated);
  r = short_env.step(kStop);
  EXPECT_TRUE(r.truncated);
  EXPECT_FALSE(r.terminated);
  EXPECT_EQ(r.message, "time limit");
}

TEST(RoverEnv, DivergenceIsFlaggedNotThrown) {
  RoverEnv env(dynamics::RoverParameters{}, flat_rigid());
  env.reset(3);
  env.sim().apply_chassis_force(Eigen::Vector3d(0.0, 0.0, 1e9));
  envs::StepResult r;
  EXPECT_NO_THROW(r = env.step(kStop));
  EXPECT_TRUE(r.diverged);
  EXPECT_TRUE(r.truncated);
  EXPECT_FALSE(r.message.empty());
  EXPECT_TRUE(r.observation.allFinite());
}

TEST(RoverEnv, PassiveModeKeepsTheGimbalStill) {
  EnvOptions o = flat_rigid();
  o.passive = true;
  RoverEnv env(dynamics::RoverParameters{}, o);
  env.reset(4);
  for (int i = 0; i < 4; ++i) env.step(ActionVector(0.0, 1.0, 1.0));  // joint rates ignored
  EXPECT_LT(std::abs(env.sim().state().gimbal_yaw), 1e-3);
  EXPECT_GT(env.metrics().progress, 0.1);
}

TEST(RoverEnv, InvalidOptionsAndActions) {
  EnvOptions o;
  o.soil = "clay";
  EXPECT_THROW(RoverEnv(dynamics::RoverParameters{}, o), std::invalid_argument);
  o = EnvOptions{};
  o.policy_dt = 0.51;  // not a whole number of 0.02 s physics steps
  EXPECT_THROW(RoverEnv(dynamics::RoverParameters{}, o), std::invalid_argument);
  RoverEnv env(dynamics::RoverParameters{}, flat_rigid());
  env.reset(0);
  EXPECT_THROW(env.step(ActionVector(NAN, 0, 0)), std::invalid_argument);
}

TEST(RoverEnv, OptionalOptionsRefuseSentinelsAndNonsense) {
  // Unset optional fields mean "the default"; a set one must be a real value, so the old
  // "0 = default" sentinel, negatives and NaN are refused, naming the field.
  EnvOptions{}.validate();
  const auto refused = [](const EnvOptions& o, const std::string& field) {
    try {
      o.validate();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what()).find("EnvOptions." + field) != std::string::npos;
    }
    return false;
  };
  for (double v : {0.0, -1.0, std::nan("")}) {
    EnvOptions o;
    o.physics_dt = v;
    EXPECT_TRUE(refused(o, "physics_dt")) << v;
    o = EnvOptions{};
    o.episode_duration = v;
    EXPECT_TRUE(refused(o, "episode_duration")) << v;
    o = EnvOptions{};
    o.slip_force_tolerance = v;
    EXPECT_TRUE(refused(o, "slip_force_tolerance")) << v;
    o = EnvOptions{};
    o.eps_slip = v;
    EXPECT_TRUE(refused(o, "eps_slip")) << v;
    o = EnvOptions{};
    o.eps_motion = v;
    EXPECT_TRUE(refused(o, "eps_motion")) << v;
  }
  EnvOptions o;
  o.obstacle_substeps = 0;
  EXPECT_TRUE(refused(o, "obstacle_substeps"));
}
