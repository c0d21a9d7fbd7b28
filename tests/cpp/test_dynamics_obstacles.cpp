// Obstacle contacts guessed like rigid ground: a wheel's contact points with a box
// emitted sticking (friction rows unbounded, checked against mu F_n after the step) go to the
// sparse solver; a wheel that slides falls back to ODE's contact with bounded friction.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "ernest/dynamics/rover_sim.hpp"
#include "snapshot_gap.hpp"

using namespace ernest::dynamics;

namespace {

using ernest::testing::body_gap;

SimOptions options(bool guess) {
  SimOptions o;
  o.friction = 0.8;
  o.guess_obstacle_contacts = guess;
  return o;
}

Commands rolling(double speed) {
  Commands c;
  c.gimbal_enabled = false;
  for (auto& w : c.wheel_speed) w = speed / RoverParameters{}.wheel_radius;
  return c;
}

// A flat rock 5 mm under the soil surface, 2 m long and wider than the rover: the wheels sink
// onto it and roll on its top (the tyres stick: they roll without slipping on the rock).
const std::vector<BoxObstacle> kSlab{{Eigen::Vector3d(1.5, 0.0, -0.055), Eigen::Vector3d(2.0, 3.0, 0.1)}};

}  // namespace

TEST(ObstacleContacts, GuessedStickingMatchesOdesBoundedSolveStepByStep) {
  // From the same state, one step with the contacts guessed sticking and one with their friction
  // bounded (ODE's pivoting): where the tyres stick both give the same LCP solution. Except where
  // a tyre's friction demand comes near mu F_n (the wheels meeting the rock's 5 mm lip, 12 of
  // 600 steps): ODE bounds a friction row by mu times the normal force of the moment it clamps
  // it, an approximation of Coulomb's law that the guessed step (and the sparse solve of a
  // sliding contact), both with the final normal force, do not share (up to 1e-5 m/s apart).
  const HeightMap hm = HeightMap::flat(8, 8, 0.25);
  RoverSim guessed(RoverParameters{}, hm, kSlab, options(true));
  RoverSim bounded(RoverParameters{}, hm, kSlab, options(false));
  guessed.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.15);
  guessed.set_commands(rolling(0.15));
  bounded.set_commands(rolling(0.15));
  int touching = 0, apart = 0;
  for (int k = 0; k < 600; ++k) {
    bounded.restore(guessed.snapshot());
    guessed.step();
    bounded.step();
    touching += guessed.solver_stats().obstacles_touched > 0;
    const double gap = body_gap(guessed.snapshot(), bounded.snapshot());
    ASSERT_LE(gap, 1e-4) << "step " << k;
    apart += gap > 1e-9;
  }
  EXPECT_LE(apart, 20);
  EXPECT_GT(touching, 300);  // the wheels are on the rock for most of the run
  const SolverStats& s = guessed.solver_stats();
  // (sub)steps solved sticking
  EXPECT_GT(s.obstacle_guessed, static_cast<std::uint64_t>(SimOptions{}.obstacle_substeps) * 300u);
  EXPECT_LT(s.obstacle_bounded, s.obstacle_guessed / 20);
  EXPECT_EQ(bounded.solver_stats().obstacle_guessed, 0u);
}

TEST(ObstacleContacts, ASlidingWheelIsSolvedWithItsFrictionBounds) {
  // The passive bogie spinning its wheels against a 0.4 m wall: the front tyres slide on its
  // face, which a sticking guess cannot hold (its friction would exceed mu F_n): those steps are
  // solved with the friction bounded, as without guesses, and the runs agree.
  const std::vector<BoxObstacle> wall{{Eigen::Vector3d(1.5, 0.0, 0.2), Eigen::Vector3d(0.3, 3.0, 0.4)}};
  const HeightMap hm = HeightMap::flat(8, 8, 0.25);
  RoverSim guessed(RoverParameters{}, hm, wall, options(true));
  RoverSim bounded(RoverParameters{}, hm, wall, options(false));
  for (RoverSim* s : {&guessed, &bounded}) {
    s->reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.2);
    s->set_commands(rolling(0.2));
    s->step_n(static_cast<int>(std::lround(10.0 / SimOptions{}.dt)));
  }
  const SolverStats& s = guessed.solver_stats();
  EXPECT_GT(s.obstacle_bounded, s.obstacle_guessed);
  EXPECT_NEAR(guessed.state().position.x(), bounded.state().position.x(), 1e-3);
  EXPECT_NEAR(guessed.state().energy / bounded.state().energy, 1.0, 0.01);
}

TEST(ObstacleContacts, RestoreOnRocksIsBitExact) {
  // The wheels' guesses (Snapshot::obstacle_mode) are state: a fresh simulation restored from a
  // snapshot taken on the rock continues bit for bit.
  const HeightMap hm = HeightMap::flat(8, 8, 0.25);
  RoverSim a(RoverParameters{}, hm, kSlab, options(true));
  a.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.15);
  a.set_commands(rolling(0.15));
  a.step_n(300);
  const Snapshot s = a.snapshot();
  a.step_n(100);
  RoverSim b(RoverParameters{}, hm, kSlab, options(true));
  b.restore(s);
  b.step_n(100);
  const Snapshot fa = a.snapshot(), fb = b.snapshot();
  EXPECT_EQ(std::memcmp(fa.bodies.data(), fb.bodies.data(), sizeof(fa.bodies)), 0);
  Snapshot bad = s;
  bad.obstacle_mode[1] = static_cast<RowState>(7);
  EXPECT_THROW(b.restore(bad), std::invalid_argument);
}
