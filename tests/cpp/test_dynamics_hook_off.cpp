// The solver hook found off. This executable is linked so that it does not
// export ernest's dxSolveLCP (tests/CMakeLists.txt: --exclude-libs), as with a libode that binds
// its call internally: ODE never reaches the fast path. The probe must say so and why, warn once
// on stderr, and every step must run on ODE's own solver.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "ernest/solver/ode_init.hpp"
#include "ernest/dynamics/rover_sim.hpp"

using namespace ernest::dynamics;
using namespace ernest::solver;

TEST(SolverHookOff, ProbeReportsItWarnsOnceAndOdeSolvesEveryStep) {
  testing::internal::CaptureStderr();
  const bool active = fast_lcp_active();
  const std::string warning = testing::internal::GetCapturedStderr();
  EXPECT_FALSE(active);
  EXPECT_NE(fast_lcp_inactive_reason().find("do not reach ernest's dxSolveLCP"),
            std::string::npos)
      << fast_lcp_inactive_reason();
  EXPECT_NE(warning.find("ernest: warning: the fast constraint solver is off"), std::string::npos)
      << warning;
  EXPECT_NE(warning.find(fast_lcp_inactive_reason()), std::string::npos) << warning;

  testing::internal::CaptureStderr();
  EXPECT_FALSE(fast_lcp_active());
  SimOptions o;  // sparse_lcp asked for, but not available through dWorldStep
  o.stepper = Stepper::Ode;
  auto sim = std::make_unique<RoverSim>(RoverParameters{}, HeightMap::flat(8, 8, 0.25),
                                        std::vector<BoxObstacle>{}, o);
  sim->reset(0.0, 0.0, 0.0);
  sim->step_n(8);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");  // warned once only
  const SolverStats& s = sim->solver_stats();
  EXPECT_FALSE(s.fast_lcp);
  EXPECT_EQ(s.steps, 8u);
  EXPECT_EQ(s.sparse_solves, 0u);
  EXPECT_EQ(s.dense_solves, 0u);  // not even counted: ODE's calls never reach ode_lcp.cpp
  EXPECT_TRUE(std::isfinite(sim->state().position.z()));

  // Our own island step (the default stepper) calls the sparse solver itself: it needs no hook.
  o.stepper = Stepper::Own;
  auto own = std::make_unique<RoverSim>(RoverParameters{}, HeightMap::flat(8, 8, 0.25),
                                        std::vector<BoxObstacle>{}, o);
  own->reset(0.0, 0.0, 0.0);
  own->step_n(8);
  const SolverStats& t = own->solver_stats();
  EXPECT_TRUE(t.fast_lcp);
  EXPECT_GE(t.sparse_solves, 8u);
  EXPECT_EQ(t.own_steps, t.sparse_solves);
  EXPECT_EQ(t.dense_solves, 0u);
  EXPECT_NEAR(own->state().position.z(), sim->state().position.z(), 1e-9);
}
