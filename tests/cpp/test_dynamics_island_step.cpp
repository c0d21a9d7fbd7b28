// Our own island step (SimOptions::stepper = Own, cpp/solver/island_step.hpp) against ODE's
// dWorldStep, the reference implementation it reproduces: from the same state (a Snapshot of
// the Ode run restored into the Own one), one step each must agree to rounding, in every
// scenario whose joints and options it covers (soft soil rolling and slipping, rocks with
// obstacle contacts, rigid ground, the gimbal's stops engaged, the drives at their limits,
// torque mode). The rounding differs (A is summed body by body, ODE by joint pairs), so the
// bound is relative: 1e-10 of the scenario's speed scale, far above the 1e-14 seen and far
// below any modelling difference (a missing row or a wrong rhs moves bodies by 1e-4 or more).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <vector>

#include "ernest/dynamics/rover_sim.hpp"
#include "snapshot_gap.hpp"

using namespace ernest::dynamics;

namespace {

using ernest::testing::body_gap;

SimOptions options(Stepper s, GroundType ground = GroundType::Soil) {
  SimOptions o;
  o.friction = 0.8;
  o.ground = ground;
  o.stepper = s;
  return o;
}

Commands rolling(double speed) {
  Commands c;
  for (auto& w : c.wheel_speed) w = speed / RoverParameters{}.wheel_radius;
  return c;
}

// Rocks in the rover's path (both wheel tracks), some yawed.
std::vector<BoxObstacle> rocks() {
  std::vector<BoxObstacle> r;
  for (int k = 0; k < 20; ++k) {
    const double x = 1.05 + 0.06 * k, y = (k % 2 ? 1 : -1) * (0.34 + 0.03 * (k % 5));
    r.push_back({Eigen::Vector3d(x, y, 0.0), Eigen::Vector3d(0.08, 0.1, 0.06 + 0.01 * (k % 3)),
                 0.3 * k, 0.0, 0.0});
  }
  return r;
}

double relative_state_gap(RoverSim& a, RoverSim& b) {
  std::vector<double> va(RoverSim::kStateVectorSize), vb(RoverSim::kStateVectorSize);
  a.state_vector(va.data());
  b.state_vector(vb.data());
  double gap = 0.0;
  for (int i = 0; i < RoverSim::kStateVectorSize; ++i)
    gap = std::max(gap, std::abs(va[i] - vb[i]) / (1.0 + std::abs(vb[i])));
  return gap;
}

struct Agreement {
  double body = 0.0, state = 0.0;
  std::uint64_t own_steps = 0, fallbacks = 0;
};

// n steps of `ode`; before each, `own` is put in ode's state; both step once and are compared.
Agreement step_by_step(RoverSim& ode, RoverSim& own, int n, const Commands& c) {
  ode.set_commands(c);
  own.set_commands(c);
  Agreement a;
  for (int k = 0; k < n; ++k) {
    own.restore(ode.snapshot());
    ode.step();
    own.step();
    a.body = std::max(a.body, body_gap(ode.snapshot(), own.snapshot()));
    a.state = std::max(a.state, relative_state_gap(own, ode));
  }
  a.own_steps = own.solver_stats().own_steps;
  a.fallbacks = own.solver_stats().own_fallbacks;
  return a;
}

constexpr double kBodyTol = 1e-10;   // [m] and [m/s] at the tyre, speeds ~0.1-1
constexpr double kStateTol = 1e-9;   // relative (forces of ~100 N are 1e-9 relative ~ 1e-7 N)

}  // namespace

TEST(IslandStep, OptionDefaultsToOwnAndIsValidated) {
  EXPECT_EQ(SimOptions{}.stepper, Stepper::Own);
  SimOptions o;
  o.stepper = static_cast<Stepper>(7);
  EXPECT_THROW(o.validate(), std::invalid_argument);
}

TEST(IslandStep, SoftSoilRollingAgreesWithDWorldStep) {
  const HeightMap hm = HeightMap::flat(12, 8, 0.25, 0, -4, -4);
  RoverSim ode(RoverParameters{}, hm, {}, options(Stepper::Ode));
  RoverSim own(RoverParameters{}, hm, {}, options(Stepper::Own));
  ode.reset(0, 0, 0, 0, 0, 0.15);
  const Agreement a = step_by_step(ode, own, 150, rolling(0.15));
  EXPECT_LE(a.body, kBodyTol);
  EXPECT_LE(a.state, kStateTol);
  EXPECT_GT(a.own_steps, 150u);  // implicit-slip re-solves and retries are attempts too
  EXPECT_EQ(a.fallbacks, 0u);
}

TEST(IslandStep, SlippingTorqueModeAndGimbalDrivesAgree) {
  // Torque mode on the wheels (explicit torques), the gimbal driven in yaw and roll with the
  // clutch engaged, on a slope where the wheels slip.
  const HeightMap hm = HeightMap::slope(0.25, 16, 8, 0.25, -6, -4);
  RoverSim ode(RoverParameters{}, hm, {}, options(Stepper::Ode));
  RoverSim own(RoverParameters{}, hm, {}, options(Stepper::Own));
  ode.reset(0, 0, 0, 0.1, -0.05, 0.0);
  Commands c;
  c.wheel_mode = ActuatorMode::Torque;
  c.wheel_torque = {6.0, -4.0, 8.0, 2.0};
  c.clutch_engage = true;
  c.yaw_rate = 0.2;
  c.roll_rate = -0.1;
  const Agreement a = step_by_step(ode, own, 120, c);
  EXPECT_LE(a.body, kBodyTol);
  EXPECT_LE(a.state, kStateTol);
  EXPECT_GT(a.own_steps, 0u);
}

TEST(IslandStep, GimbalStopsAndDrivesAtTheirLimitsAgree) {
  // Yaw driven into its stop (the universal joint's stop row) and the wheels commanded far
  // beyond what their current-limited torque reaches (drive rows at their bounds).
  const HeightMap hm = HeightMap::flat(12, 8, 0.25, 0, -4, -4);
  RoverSim ode(RoverParameters{}, hm, {}, options(Stepper::Ode));
  RoverSim own(RoverParameters{}, hm, {}, options(Stepper::Own));
  const RoverParameters p;
  ode.reset(0, 0, 0, p.yaw_limit - 0.01, p.roll_limit - 0.01, 0.0);
  Commands c = rolling(3.0);
  c.yaw_rate = 0.5;
  c.clutch_engage = true;
  c.roll_rate = 0.5;
  const Agreement a = step_by_step(ode, own, 150, c);
  EXPECT_LE(a.body, kBodyTol);
  EXPECT_LE(a.state, kStateTol);
  EXPECT_GE(std::abs(own.state().gimbal_yaw), p.yaw_limit - 1e-3);  // the stop was reached
  EXPECT_GT(a.own_steps, 0u);
  EXPECT_GT(a.fallbacks, 0u);  // attempts pivoted by ODE (every row with its bounds)
}

TEST(IslandStep, RocksWithObstacleContactsAgree) {
  const HeightMap hm = HeightMap::flat(12, 8, 0.25, 0, -4, -4);
  RoverSim ode(RoverParameters{}, hm, rocks(), options(Stepper::Ode));
  RoverSim own(RoverParameters{}, hm, rocks(), options(Stepper::Own));
  ode.reset(0, 0, 0, 0, 0, 0.15);
  const Agreement a = step_by_step(ode, own, 480, rolling(0.15));
  EXPECT_GT(ode.solver_stats().obstacle_guessed + ode.solver_stats().obstacle_bounded, 60u);
  EXPECT_LE(a.body, kBodyTol);
  EXPECT_LE(a.state, kStateTol);
  EXPECT_GT(a.own_steps, 0u);
}

TEST(IslandStep, RigidGroundAgrees) {
  // Rigid ground: sliding tyres' friction rows bounded by mu F_n (findex) go to dWorldStep and
  // ODE's solver with the Coulomb correction (own_fallbacks), sticking ones are ours.
  const HeightMap hm = HeightMap::slope(0.2, 16, 8, 0.25, -6, -4);
  RoverSim ode(RoverParameters{}, hm, {}, options(Stepper::Ode, GroundType::Rigid));
  RoverSim own(RoverParameters{}, hm, {}, options(Stepper::Own, GroundType::Rigid));
  ode.reset(0, 0, 0, 0, 0, 0.1);
  const Agreement a = step_by_step(ode, own, 150, rolling(0.3));
  EXPECT_LE(a.body, kBodyTol);
  EXPECT_LE(a.state, kStateTol);
  EXPECT_GT(a.own_steps, 0u);
  EXPECT_GT(a.fallbacks, 0u);  // the fallback path ran and agrees too
}

// Two runs from the same start, each on its own, 400 steps (0.6 m): the distance travelled and
// the energy. Per-step differences of ~1e-15 stay that small on soil alone (slip and the soil's
// damping are dissipative); rock contacts amplify them (a contact's normal row switching on or
// off, a guess held or not, on a rounding tie): ~2e-8 m after 400 steps on these rocks, still
// five orders of magnitude below a millimetre. The bounds are 50x the measured differences.
void trajectories_agree(const std::vector<BoxObstacle>& obstacles, double dx_tol, double de_tol) {
  const HeightMap hm = HeightMap::flat(12, 8, 0.25, 0, -4, -4);
  RoverSim ode(RoverParameters{}, hm, obstacles, options(Stepper::Ode));
  RoverSim own(RoverParameters{}, hm, obstacles, options(Stepper::Own));
  for (RoverSim* s : {&ode, &own}) {
    s->reset(0, 0, 0, 0, 0, 0.15);
    s->set_commands(rolling(0.15));
    s->step_n(400);
  }
  const double dx = ode.state().position.x() - own.state().position.x();
  EXPECT_GT(ode.state().position.x(), 0.6);
  EXPECT_LE(std::abs(dx), dx_tol);
  const double e_ode = ode.kinetic_energy() + ode.potential_energy();
  const double e_own = own.kinetic_energy() + own.potential_energy();
  EXPECT_LE(std::abs(e_ode - e_own), de_tol * std::abs(e_ode));
  EXPECT_EQ(own.solver_stats().own_fallbacks, 0u);
}

TEST(IslandStep, TrajectoriesAgreeOnSoil) { trajectories_agree({}, 1e-12, 1e-13); }

TEST(IslandStep, TrajectoriesAgreeOnRocks) { trajectories_agree(rocks(), 1e-6, 1e-7); }

TEST(IslandStep, SameSeedSameBitsAndRestoreIsExact) {
  const HeightMap hm = HeightMap::flat(12, 8, 0.25, 0, -4, -4);
  RoverSim a(RoverParameters{}, hm, rocks(), options(Stepper::Own));
  RoverSim b(RoverParameters{}, hm, rocks(), options(Stepper::Own));
  for (RoverSim* s : {&a, &b}) {
    s->reset(0, 0, 0, 0, 0, 0.15);
    s->set_commands(rolling(0.15));
    s->step_n(60);
  }
  EXPECT_EQ(body_gap(a.snapshot(), b.snapshot()), 0.0);
  const Snapshot mid = a.snapshot();
  a.step_n(40);
  const Snapshot end = a.snapshot();
  a.restore(mid);
  a.step_n(40);
  EXPECT_EQ(body_gap(a.snapshot(), end), 0.0);
}

namespace {

// Step k's commands for the resolve test: every drive moves, the clutch engages and releases and
// the AGS is switched off for a while, so drive rows change their modes (and the drives' joint
// parameters change) between the attempts of some steps.
Commands varied(int k) {
  Commands c;
  for (int w = 0; w < 4; ++w) c.wheel_speed[w] = 1.2 + 0.4 * std::sin(0.05 * k + 0.7 * w);
  c.yaw_rate = 0.3 * std::sin(0.03 * k);
  c.roll_rate = 0.1 * std::cos(0.04 * k);
  c.clutch_engage = (k / 70) % 2 == 1;
  c.gimbal_enabled = !(k >= 150 && k < 190);
  return c;
}

// The same run with SimOptions::resolve_rhs_only on and off: every step's state vector (drive
// torques, loads, FTS wrenches) and bodies to the bit, and the same SolverStats but for the
// counts of resolves (right-hand sides, and new caps). Returns the rhs resolves with it on.
std::uint64_t resolves_give_the_bits_of_rebuilds(const HeightMap& hm,
                                                 const std::vector<BoxObstacle>& obstacles,
                                                 int steps, double x0) {
  SimOptions on = options(Stepper::Own), off = on;
  off.resolve_rhs_only = false;
  EXPECT_TRUE(on.resolve_rhs_only);  // the default
  RoverSim a(RoverParameters{}, hm, obstacles, on), b(RoverParameters{}, hm, obstacles, off);
  a.reset(x0, 0, 0, 0, 0, 0.15);
  b.reset(x0, 0, 0, 0, 0, 0.15);
  int touching = 0;
  std::vector<double> va(RoverSim::kStateVectorSize), vb(RoverSim::kStateVectorSize);
  int first_difference = -1;
  for (int k = 0; k < steps && first_difference < 0; ++k) {
    a.set_commands(varied(k));
    b.set_commands(varied(k));
    a.step();
    b.step();
    a.state_vector(va.data());
    b.state_vector(vb.data());
    const Snapshot sa = a.snapshot(), sb = b.snapshot();
    bool same = std::memcmp(va.data(), vb.data(), va.size() * sizeof(double)) == 0;
    for (std::size_t i = 0; i < sa.bodies.size(); ++i) {
      const Snapshot::Body &x = sa.bodies[i], &y = sb.bodies[i];
      same = same && std::memcmp(x.pos.data(), y.pos.data(), sizeof(double) * 3) == 0 &&
             std::memcmp(x.lin.data(), y.lin.data(), sizeof(double) * 3) == 0 &&
             std::memcmp(x.ang.data(), y.ang.data(), sizeof(double) * 3) == 0 &&
             std::memcmp(x.quat.data(), y.quat.data(), sizeof(double) * 4) == 0;
    }
    if (!same) first_difference = k;
    touching += a.solver_stats().obstacles_touched > 0;
  }
  EXPECT_EQ(first_difference, -1) << "the runs parted at this step";
  const SolverStats &x = a.solver_stats(), &y = b.solver_stats();
  const std::uint64_t fa[] = {x.steps, x.first_guess, x.later_guess, x.pivoted, x.lcp_errors,
                              x.sparse_solves, x.dense_solves, x.slip_solves, x.slip_driving,
                              x.obstacle_guessed, x.obstacle_bounded, x.obstacle_explicit,
                              x.obstacle_implicit, x.own_steps, x.own_fallbacks, x.plans_made,
                              x.plans_grown};
  const std::uint64_t fb[] = {y.steps, y.first_guess, y.later_guess, y.pivoted, y.lcp_errors,
                              y.sparse_solves, y.dense_solves, y.slip_solves, y.slip_driving,
                              y.obstacle_guessed, y.obstacle_bounded, y.obstacle_explicit,
                              y.obstacle_implicit, y.own_steps, y.own_fallbacks, y.plans_made,
                              y.plans_grown};
  for (std::size_t i = 0; i < std::size(fa); ++i) EXPECT_EQ(fa[i], fb[i]) << "SolverStats field " << i;
  EXPECT_EQ(y.rhs_resolves, 0u);
  EXPECT_EQ(y.cap_resolves, 0u);
  EXPECT_LT(x.rhs_resolves + x.cap_resolves, x.own_steps);
  EXPECT_GT(x.cap_resolves, 0u) << "slip re-solves that moved the caps must take the caps path";
  EXPECT_GE(touching, obstacles.empty() ? 0 : 100) << "the rocks must be touched";
  return x.rhs_resolves;
}

}  // namespace

TEST(IslandStep, RightHandSideResolvesGiveTheBitsOfRebuilds) {
  // Rocks in both tracks (obstacle contacts with friction rows, impacts: most level-only
  // re-solves), and a 12 deg slope of M90 where the wheels slip.
  const std::uint64_t rocks_resolves =
      resolves_give_the_bits_of_rebuilds(HeightMap::flat(12, 8, 0.25, 0, -4, -4), rocks(), 400, 0.4);
  EXPECT_GE(rocks_resolves, 20u) << "the rocks must make level-only re-solves";
  resolves_give_the_bits_of_rebuilds(HeightMap::slope(12.0 * M_PI / 180.0, 16, 8, 0.25, -6, -4),
                                     {}, 300, 0.0);
}
