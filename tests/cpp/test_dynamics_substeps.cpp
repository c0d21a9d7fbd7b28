// Steps in contact with an obstacle taken as substeps (SimOptions::obstacle_substeps): the passive
// bogie spinning its wheels against a wall (the Bickler trap) climbs it and falls back at fine
// steps, and would settle at coarse ones if the implicit slip (backward Euler in seed 004 eq 12)
// held the wheel at the stall, where the slip grows with the forward speed and drives the motion. With the
// slip taken from the step's start where it drives (rover_step.cpp), 1 substep reproduces the
// fine steps here; with the obstacle step split where a wheel's slip grows fast
// (obstacle_contacts.cpp) 1 is the default (benchmarks/RESULTS.md, "Step size and step
// independence"), and these tests hold for it.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ernest/dynamics/rover_sim.hpp"

using namespace ernest::dynamics;

namespace {

struct WallRun {
  double energy = 0.0;        // [J] positive electrical energy of the drives
  double x = 0.0;             // final chassis x [m]
  double front = 0.0;         // final front-left wheel's leading edge x [m]
};

// The passive bogie (gimbal off, as Table 6's baseline) on flat M90 drives at 0.2 m/s into a
// 0.4 m wall (taller than the 0.34 m wheels, like the Bickler trap's boxes) and keeps pushing.
WallRun push_wall(double dt, int substeps, double seconds) {
  SimOptions o;
  o.dt = dt;
  o.obstacle_substeps = substeps;
  o.friction = 0.7;
  o.soil.eps_slip = 1e4;  // envs::EnvOptions defaults
  o.soil.eps_motion = 0.01;
  const std::vector<BoxObstacle> wall{{Eigen::Vector3d(1.5, 0.0, 0.2), Eigen::Vector3d(0.3, 3.0, 0.4)}};
  RoverSim sim(RoverParameters{}, HeightMap::flat(8, 8, 0.25), wall, o);
  sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.2);
  Commands c;
  c.gimbal_enabled = false;
  for (auto& w : c.wheel_speed) w = 0.2 / RoverParameters{}.wheel_radius;
  sim.set_commands(c);
  WallRun r;
  const int n = static_cast<int>(std::lround(seconds / dt));
  sim.step_n(n);
  r.energy = sim.state().energy;
  r.x = sim.state().position.x();
  r.front = sim.state().wheel_position[0].x() + RoverParameters{}.wheel_radius;
  return r;
}

}  // namespace

TEST(ObstacleSubsteps, AStepWithSubstepsMatchesFineSteps) {
  // The default substeps while touching the wall vs a simulation at dt / 8 throughout: the same
  // outcome where it matters; the approach (no contact, full steps) differs by its own error.
  const double dt = SimOptions{}.dt;
  const WallRun sub = push_wall(dt, SimOptions{}.obstacle_substeps, 12.0);
  const WallRun fine = push_wall(dt / 8, 1, 12.0);
  EXPECT_NEAR(sub.x, fine.x, 0.01);
  EXPECT_NEAR(sub.energy / fine.energy, 1.0, 0.05);
}

TEST(ObstacleSubsteps, WallStallEnergyDoesNotDependOnTheStep) {
  // Step independence with the default substeps: dt and dt / 4 within 5 % of energy and 1 cm.
  const int n = SimOptions{}.obstacle_substeps;
  const double dt = SimOptions{}.dt;
  const WallRun a = push_wall(dt, n, 12.0);
  const WallRun b = push_wall(dt / 4, n, 12.0);
  EXPECT_NEAR(a.x, b.x, 0.01);
  EXPECT_NEAR(a.energy / b.energy, 1.0, 0.05);
  // The rover is stopped by the wall (its face at x = 1.35 m), not by the soil.
  EXPECT_NEAR(a.front, 1.35, 0.05);
}

TEST(ObstacleSubsteps, OneSubstepOnSoilMatchesFineSteps) {
  // No substeps at the default step against dt / 8 throughout: the wheel climbs the face and
  // falls back at both (drive energy 763 J vs 788 J; it was 381 J while the implicit slip held
  // the wheel at the stall). dt / 4 within the same bounds.
  const double dt = SimOptions{}.dt;
  const WallRun one = push_wall(dt, 1, 12.0);
  const WallRun quarter = push_wall(dt / 4, 1, 12.0);
  const WallRun fine = push_wall(dt / 8, 1, 12.0);
  EXPECT_NEAR(one.x, fine.x, 0.01);
  EXPECT_NEAR(one.energy / fine.energy, 1.0, 0.05);
  EXPECT_NEAR(quarter.x, fine.x, 0.01);
  EXPECT_NEAR(quarter.energy / fine.energy, 1.0, 0.05);
}

TEST(ObstacleSubsteps, OptionIsValidated) {
  SimOptions o;
  o.obstacle_substeps = 0;
  EXPECT_THROW(o.validate(), std::invalid_argument);
  o.obstacle_substeps = 65;
  EXPECT_THROW(o.validate(), std::invalid_argument);
  o.obstacle_substeps = 16;
  EXPECT_NO_THROW(o.validate());
}
