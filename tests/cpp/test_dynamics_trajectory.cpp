// Pinned trajectories: fixed scenarios stepped with fixed command sequences, the bit patterns of
// every step's 65-value state vector (and the final bodies) hashed and compared with hashes pinned
// below. A change of the core that moves code without changing the arithmetic keeps every hash; a
// one-bit change anywhere in a trajectory changes its hash (TrajectoryHash.OneUlpChangesTheHash
// shows it on the start state).
//
// The bits depend on the compiler, its flags and the Eigen/ODE builds: the pins hold for the
// Release build `./run test` makes (g++ -O3 of Debian 12, -fno-math-errno -fno-trapping-math) and
// for its ASan + UBSan build (the same bits). A change that is meant to change the physics (or a
// new toolchain) re-pins: run this test, check the trajectories' physics with the other dynamics
// tests, and copy the printed hashes into the pins below, saying why in the commit. Each scenario
// is pinned on both steppers (Own and ODE's dWorldStep) and both wheel-rock contacts.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "ernest/dynamics/batch_stepper.hpp"
#include "ernest/dynamics/rover_sim.hpp"

using namespace ernest::dynamics;

namespace {

// FNV-1a over bytes: simple, order-sensitive, and every input bit reaches the result.
struct Hash {
  std::uint64_t h = 1469598103934665603ull;
  void bytes(const void* data, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  }
  void values(const double* v, std::size_t n) { bytes(v, n * sizeof(double)); }
  void state_of(const RoverSim& sim) {
    double s[RoverSim::kStateVectorSize];
    sim.state_vector(s);
    values(s, RoverSim::kStateVectorSize);
  }
  void bodies_of(const RoverSim& sim) {
    const Snapshot snap = sim.snapshot();
    for (const Snapshot::Body& b : snap.bodies) {
      values(b.pos.data(), 3);
      values(b.lin.data(), 3);
      values(b.ang.data(), 3);
      values(b.quat.data(), 4);
    }
  }
};

// Step k's commands: every actuator moves, the clutch engages and releases, the AGS is switched
// off for a while (brakes), so every drive row and the clutch logic take part.
Commands command(int k) {
  Commands c;
  for (int w = 0; w < 4; ++w) c.wheel_speed[w] = 1.0 + 0.3 * std::sin(0.05 * k + 0.7 * w);
  c.yaw_rate = 0.2 * std::sin(0.03 * k);
  c.roll_rate = 0.1 * std::cos(0.04 * k);
  c.clutch_engage = (k / 80) % 2 == 1;
  c.gimbal_enabled = !(k >= 200 && k < 240);
  return c;
}

// Runs `steps` steps from the rover's current state, hashing the state after each.
void run(RoverSim& sim, int first, int steps, Hash& hash, int* touching = nullptr) {
  for (int k = first; k < first + steps; ++k) {
    sim.set_commands(command(k));
    sim.step();
    hash.state_of(sim);
    if (touching) *touching += sim.solver_stats().obstacles_touched > 0;
  }
  hash.bodies_of(sim);
}

std::vector<BoxObstacle> rocks() {
  std::vector<BoxObstacle> boxes;
  for (int i = 0; i < 8; ++i)
    boxes.push_back({Eigen::Vector3d(0.45 + 0.2 * i, (i % 3 - 1) * 0.35, 0.02),
                     Eigen::Vector3d(0.15, 0.2, 0.08), 0.3 * i, 0.05 * i, 0.1});
  return boxes;
}

// A pinned configuration: who steps the bodies and how a wheel's contact with a rock is found.
struct Config {
  Stepper stepper;
  WheelObstacleContact contact;
};

SimOptions with(Config c) {
  SimOptions o;
  o.stepper = c.stepper;
  o.wheel_obstacle_contact = c.contact;
  return o;
}

std::uint64_t flat_m90(Config stepper) {
  RoverSim sim(RoverParameters{}, HeightMap::flat(12, 10, 0.25), {}, with(stepper));
  sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.1);
  Hash h;
  run(sim, 0, 400, h);
  return h.h;
}

std::uint64_t rock_field(Config stepper, int& touching) {
  SimOptions o = with(stepper);
  o.seed = 5;  // the friction draw
  RoverSim sim(RoverParameters{}, HeightMap::flat(12, 10, 0.25), rocks(), o);
  sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.15);
  Hash h;
  run(sim, 0, 300, h, &touching);
  return h.h;
}

std::uint64_t slope(Config stepper) {  // 12 deg of M90 uphill, and rigid ground on 10 deg
  Hash h;
  RoverSim soil(RoverParameters{}, HeightMap::slope(12.0 * M_PI / 180.0, 30, 10, 0.25, -15, -5),
                {}, with(stepper));
  soil.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.1);
  run(soil, 0, 300, h);
  SimOptions o = with(stepper);
  o.ground = GroundType::Rigid;
  o.friction = 0.7;
  RoverSim rigid(RoverParameters{}, HeightMap::slope(10.0 * M_PI / 180.0, 30, 10, 0.25, -15, -5),
                 {}, o);
  rigid.reset(0.0, 0.0, 0.3, 0.0, 0.0, 0.0);
  run(rigid, 0, 200, h);
  return h.h;
}

std::uint64_t batch(Config who) {  // three rovers on two threads, four steps per call
  std::vector<std::shared_ptr<RoverSim>> sims;
  for (int i = 0; i < 3; ++i) {
    SimOptions o = with(who);
    o.seed = 20 + i;
    sims.push_back(std::make_shared<RoverSim>(RoverParameters{}, HeightMap::flat(12, 10, 0.25),
                                              i == 1 ? std::vector<BoxObstacle>{} : rocks(), o));
    sims.back()->reset(0.0, 0.1 * i, 0.05 * i, 0.0, 0.0, 0.15);
  }
  BatchStepper stepper(sims, 2);
  std::vector<double> cmd(3 * RoverSim::kCommandSize), out(3 * RoverSim::kStateVectorSize);
  Hash h;
  for (int call = 0; call < 60; ++call) {
    for (int i = 0; i < 3; ++i) {
      double* c = cmd.data() + i * RoverSim::kCommandSize;
      for (int w = 0; w < 4; ++w) c[w] = 1.0 + 0.2 * std::sin(0.2 * call + i + w);
      c[4] = 0.2 * std::sin(0.1 * call);
      c[5] = 0.1 * std::cos(0.15 * call);
      c[6] = 1.0;
      c[7] = (call / 20) % 2 == 1 ? 1.0 : 0.0;
    }
    stepper.step(cmd.data(), 4, out.data());
    h.values(out.data(), out.size());
  }
  for (const auto& s : sims) h.bodies_of(*s);
  return h.h;
}

// 150 steps, a snapshot, 150 more; restored, the same 150 again: the restored run repeats them.
std::uint64_t snapshot_restore(Config stepper) {
  SimOptions o = with(stepper);
  o.seed = 9;
  RoverSim sim(RoverParameters{}, HeightMap::flat(12, 10, 0.25), rocks(), o);
  sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.15);
  Hash first, second, again;
  run(sim, 0, 150, first);
  const Snapshot s = sim.snapshot();
  run(sim, 150, 150, second);
  sim.restore(s);
  run(sim, 150, 150, again);
  EXPECT_EQ(second.h, again.h) << "restore() did not repeat the run bit for bit";
  first.bytes(&second.h, sizeof second.h);
  first.bytes(&again.h, sizeof again.h);
  return first.h;
}

// The pins, one set per stepper (SimOptions::stepper: Own, our own island step, and Ode,
// dWorldStep) and wheel-rock contact (SimOptions::wheel_obstacle_contact: Ode, ODE's cylinder-box
// merged, the default, and Exact), Release build. Own and Ode agree to rounding
// (test_dynamics_island_step: ~1e-15 m per step from the same state) but not in the last bits:
// Own forms A = J M⁻¹ Jᵀ body by body where ODE sums it joint pair by joint pair. Exact gives
// another depth, normal and point where ODE's axis is not the exact one (a box edge against a
// rim), which moves rock_field, batch and snapshot_restore; flat_m90 and slope have no rocks and
// keep the default contact's pins. The Own pins hold with SimOptions::resolve_rhs_only on (the
// default) and off: those re-solves give the bits of a rebuild (test_dynamics_island_step
// RightHandSideResolvesGiveTheBitsOfRebuilds). Besides the toolchain, what sets the last bits:
// the implicit slip's loop accepts any slips and levels within slip_force_tolerance, so where it
// starts (SimOptions::slip_warm_start) and how it iterates (the slips kept once they agree with
// eq 12 to kSlipTolerance) pick the point within it; SparseLdlt's own dense kernel has its own
// order of operations; solve_clamped solves one column per normal force,
// A_SS⁻¹ (sum_i s_i mu_i A_Si), for a rock contact sliding with both friction rows at their
// Coulomb bounds.
struct Pinned {
  std::uint64_t flat_m90, rock_field, slope, batch, snapshot_restore;
};
constexpr Pinned kPinnedOde{0x1561163a1a07ec3bull, 0xd4737a282d3fc135ull, 0xb027c6f8b0655a9dull,
                            0xf9458d0408effcf9ull, 0x1e1cc53aca2bbdccull};
constexpr Pinned kPinnedOwn{0x2133bbcc30f297d0ull, 0xc629a1e3a74def62ull, 0x40a0fef84ab5cd8dull,
                            0xa017290b0265fd43ull, 0x0a8efc93c7818c0aull};
// kPinnedOwnExact and kPinnedOdeExact pin Exact on both steppers.
constexpr Pinned kPinnedOdeExact{0x1561163a1a07ec3bull, 0xac467cb3311a3200ull,
                                 0xb027c6f8b0655a9dull, 0x1dd951c01c312e69ull,
                                 0x4a562ef9f972bb19ull};
constexpr Pinned kPinnedOwnExact{0x2133bbcc30f297d0ull, 0x9d0d59ba54eed38dull,
                                 0x40a0fef84ab5cd8dull, 0x9098b2890cee568full,
                                 0x77c0d73d105260f4ull};

void expect_pinned(const char* name, std::uint64_t got, std::uint64_t pinned) {
  EXPECT_EQ(got, pinned) << name << ": the trajectory's bits changed; if the change is meant "
                         << "(see this file's header), re-pin " << name << " = 0x" << std::hex
                         << got << "ull";
}

}  // namespace

// Each pinned scenario on both steppers, the default (Own) and ODE's dWorldStep, and with both
// wheel–rock contacts, the default (ODE's collider) and Exact.
class TrajectoryHash : public ::testing::TestWithParam<Config> {
 protected:
  const Pinned& pinned() const {
    const bool own = GetParam().stepper == Stepper::Own;
    if (GetParam().contact == WheelObstacleContact::Exact)
      return own ? kPinnedOwnExact : kPinnedOdeExact;
    return own ? kPinnedOwn : kPinnedOde;
  }
};

INSTANTIATE_TEST_SUITE_P(
    Steppers, TrajectoryHash,
    ::testing::Values(Config{Stepper::Own, WheelObstacleContact::Exact},
                      Config{Stepper::Ode, WheelObstacleContact::Exact},
                      Config{Stepper::Own, WheelObstacleContact::Ode},
                      Config{Stepper::Ode, WheelObstacleContact::Ode}),
    [](const ::testing::TestParamInfo<Config>& i) {
      return std::string(i.param.stepper == Stepper::Own ? "Own" : "Ode") +
             (i.param.contact == WheelObstacleContact::Exact ? "Exact" : "OdeContact");
    });

TEST_P(TrajectoryHash, FlatM90) {
  expect_pinned("flat_m90", flat_m90(GetParam()), pinned().flat_m90);
}

TEST_P(TrajectoryHash, RockFieldWithBoxesTouched) {
  int touching = 0;
  const std::uint64_t h = rock_field(GetParam(), touching);
  EXPECT_GE(touching, 50) << "the rocks must be touched for the hash to cover their contacts";
  expect_pinned("rock_field", h, pinned().rock_field);
}

TEST_P(TrajectoryHash, SoilAndRigidSlopes) {
  expect_pinned("slope", slope(GetParam()), pinned().slope);
}

TEST_P(TrajectoryHash, BatchStepper) { expect_pinned("batch", batch(GetParam()), pinned().batch); }

TEST_P(TrajectoryHash, SnapshotRestore) {
  expect_pinned("snapshot_restore", snapshot_restore(GetParam()), pinned().snapshot_restore);
}

TEST(TrajectoryHashSensitivity, OneUlpChangesTheHash) {
  // The hash is sensitive to the last bit: one ulp on one coordinate of the start state changes
  // it (the perturbation grows through the dynamics, and its own bits are hashed at once).
  const auto hash_from = [](bool perturb) {
    RoverSim sim(RoverParameters{}, HeightMap::flat(12, 10, 0.25));
    sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.1);
    Snapshot s = sim.snapshot();
    if (perturb) s.bodies[0].lin[0] = std::nextafter(s.bodies[0].lin[0], 1.0);
    sim.restore(s);
    Hash h;
    run(sim, 0, 20, h);
    return h.h;
  };
  EXPECT_EQ(hash_from(false), hash_from(false));
  EXPECT_NE(hash_from(false), hash_from(true));
}
