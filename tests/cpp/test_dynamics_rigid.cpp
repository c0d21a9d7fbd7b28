// Rigid ground (seed 004 §3.4: a linear spring–damper normal contact with Coulomb friction):
// a parked rover holds on a slope inside the friction cone and slides at the block-on-incline
// acceleration outside it, at the default step and at a quarter of it.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "ernest/dynamics/rover_sim.hpp"

using namespace ernest::dynamics;

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kSlope = 15.0 * kDeg;

// Parked on a rigid 15 deg slope rising along +x, facing uphill: drives holding the wheels at
// zero speed, clutch engaged, gimbal on (yaw and roll servoed still) or braked.
std::unique_ptr<RoverSim> parked(double mu, double dt, bool gimbal_enabled) {
  SimOptions o;
  o.ground = GroundType::Rigid;
  o.friction = mu;
  o.dt = dt;
  auto sim = std::make_unique<RoverSim>(RoverParameters{}, HeightMap::slope(kSlope, 40, 10, 0.25, -30, -5),
                                        std::vector<BoxObstacle>{}, o);
  sim->reset(0.0, 0.0, 0.0);
  Commands c;
  c.gimbal_enabled = gimbal_enabled;
  c.clutch_engage = true;
  sim->set_commands(c);
  return sim;
}

// Chassis position along the slope's downhill direction.
double downhill(const RoverSim& sim) {
  const Eigen::Vector3d d(-std::cos(kSlope), 0.0, -std::sin(kSlope));
  return sim.state().position.dot(d);
}

int steps_for(double seconds, double dt) { return static_cast<int>(std::lround(seconds / dt)); }

}  // namespace

class RigidSlope : public ::testing::TestWithParam<double> {};  // the step's divisor

TEST_P(RigidSlope, ParkedRoverInsideTheFrictionConeHolds) {
  // mu 0.7 > tan 15 deg = 0.27: Coulomb friction holds the parked rover; after settling on the
  // contact springs it moves less than 1 mm in 20 s.
  const double dt = SimOptions{}.dt / GetParam();
  for (const bool gimbal : {true, false}) {
    SCOPED_TRACE(gimbal ? "gimbal servoed" : "gimbal braked");
    auto sim = parked(0.7, dt, gimbal);
    sim->step_n(steps_for(3.0, dt));
    ASSERT_EQ(sim->state().clutch, ClutchState::Engaged);
    const Eigen::Vector3d x0 = sim->state().position;
    const double s0 = downhill(*sim);
    sim->step_n(steps_for(20.0, dt));
    const double moved = (sim->state().position - x0).norm();
    std::printf("dt %.5f gimbal %d: settled at %.3f mm downhill, moved %.4f mm in 20 s\n", dt,
                gimbal, 1e3 * s0, 1e3 * moved);
    EXPECT_LT(moved, 1e-3);
  }
}

TEST_P(RigidSlope, RoverOutsideTheFrictionConeSlidesAtTheBlockOnInclineAcceleration) {
  // mu 0.2 < tan 15 deg: every wheel slides and the rover accelerates down the slope at
  // g (sin theta - mu cos theta), whatever the load distribution over the wheels (the friction
  // forces add up to mu times the total normal force).
  const double dt = SimOptions{}.dt / GetParam();
  const double mu = 0.2;
  auto sim = parked(mu, dt, true);
  const double g = SimOptions{}.soil.gravity;
  const double expected = g * (std::sin(kSlope) - mu * std::cos(kSlope));
  sim->step_n(steps_for(1.0, dt));  // sliding by now
  // Least-squares slope of the downhill speed over 2 s.
  const int n = steps_for(2.0, dt);
  double st = 0, sv = 0, stt = 0, stv = 0;
  const Eigen::Vector3d d(-std::cos(kSlope), 0.0, -std::sin(kSlope));
  for (int k = 0; k < n; ++k) {
    sim->step();
    const double t = k * dt, v = sim->state().linear_velocity.dot(d);
    st += t, sv += v, stt += t * t, stv += t * v;
  }
  const double accel = (n * stv - st * sv) / (n * stt - st * st);
  std::printf("dt %.5f: sliding at %.4f m/s^2, block on incline %.4f (%+.2f %%)\n", dt, accel,
              expected, 100.0 * (accel / expected - 1.0));
  EXPECT_NEAR(accel, expected, 0.05 * expected);
}

INSTANTIATE_TEST_SUITE_P(Steps, RigidSlope, ::testing::Values(1.0, 4.0),
                         [](const auto& info) { return info.param == 1.0 ? "dt" : "dt_over_4"; });

TEST(RigidGround, RollingTracksTheCommandAtEitherStep) {
  // Sticking tyres roll: at 0.2 m/s on flat rigid ground the rover covers 0.2 m/s x 10 s (less
  // the start from rest), the same at the default step and at a quarter of it.
  std::array<double, 2> travelled{};
  for (int s = 0; s < 2; ++s) {
    SimOptions o;
    o.ground = GroundType::Rigid;
    o.friction = 0.8;
    o.dt = SimOptions{}.dt / (s == 0 ? 1.0 : 4.0);
    RoverSim sim(RoverParameters{}, HeightMap::flat(10, 10, 0.25), {}, o);
    sim.reset(-3.0, 0.0, 0.0);
    Commands c;
    for (auto& w : c.wheel_speed) w = 0.2 / RoverParameters{}.wheel_radius;
    sim.set_commands(c);
    const double x0 = sim.state().position.x();
    sim.step_n(steps_for(10.0, o.dt));
    travelled[s] = sim.state().position.x() - x0;
    EXPECT_NEAR(sim.state().linear_velocity.x(), 0.2, 0.002) << o.dt;
    EXPECT_NEAR(travelled[s], 2.0, 0.02) << o.dt;
    EXPECT_LT(std::abs(sim.state().position.y()), 1e-3) << o.dt;
  }
  std::printf("travelled %.4f m at dt, %.4f m at dt / 4\n", travelled[0], travelled[1]);
  EXPECT_NEAR(travelled[0], travelled[1], 0.01 * travelled[1]);
}

TEST(RigidGround, RestoreRepeatsTheTyreDeflectionsBitForBit) {
  // The tyres' deflections are state (Snapshot::rigid_deflection): a parked rover restored
  // mid-run, then driven off, repeats the run exactly.
  auto sim = parked(0.7, SimOptions{}.dt, true);
  sim->step_n(20);  // deflected, still settling
  const Snapshot s = sim->snapshot();
  Commands c = sim->commands();
  for (auto& w : c.wheel_speed) w = 1.0;
  const auto run = [&] {
    sim->set_commands(c);
    sim->step_n(40);
    return sim->state().position;
  };
  const Eigen::Vector3d first = run();
  sim->restore(s);
  const Eigen::Vector3d second = run();
  EXPECT_EQ(first, second);
  EXPECT_GT(std::abs(s.rigid_deflection[2][0]) + std::abs(s.rigid_deflection[2][2]), 1e-4);
}
