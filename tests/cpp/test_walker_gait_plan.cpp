// FootFall's skeleton gait (seed 003 §5.3.1): reverse-wave order, step lengths by successive IK,
// body shifts with all feet down, periodic after the second cycle on flat ground, every stance
// statically stable.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "ernest/statics/stability.hpp"
#include "ernest/walker/gait_planner.hpp"
#include "ernest/walker/leg_ik.hpp"
#include "test_util.hpp"

using namespace ernest::walker;
using ernest::testing::invalid_argument_message;

namespace {
constexpr double kPi = 3.14159265358979323846;
}

TEST(WalkerGaitPlan, ReverseWaveIsFrontToRearLeftFirst) {
  const WalkerModel m(sdm_b_parameters());
  // Legs counter-clockwise from +x: travelling +x, leg 0 is in front, 1 front-left, 5 front-right.
  EXPECT_EQ(reverse_wave_sequence(m, 0.0), (std::vector<int>{0, 1, 5, 2, 4, 3}));
  // Travelling +y: legs 1 and 2 in front, 2 is on the left of +y (x < 0).
  EXPECT_EQ(reverse_wave_sequence(m, 0.5 * kPi), (std::vector<int>{2, 1, 3, 0, 4, 5}));
  // Travelling 30°: between legs 0 and 1, 1 on the left.
  EXPECT_EQ(reverse_wave_sequence(m, kPi / 6), (std::vector<int>{1, 0, 2, 5, 3, 4}));
}

TEST(WalkerGaitPlan, BecomesPeriodicAfterTheSecondCycleWithEveryStanceStable) {
  const WalkerModel m(sdm_b_parameters());
  GaitPlannerOptions o;
  o.cycles = 4;
  o.max_step = 0.8;
  const GaitPlan p = plan_gait(m, m.standard_body_pose().translation(), m.standard_configuration(), o);
  std::printf("steps\n");
  for (int c = 0; c < o.cycles; ++c) {
    for (int i = 0; i < 6; ++i) std::printf(" %.4f", p.step_lengths(c, i));
    std::printf("   shifts");
    for (int i = 0; i < 6; ++i) std::printf(" %.4f", p.shift_lengths(c, i));
    std::printf("\n");
  }
  std::printf("ik tests %d, %.3f s\n", p.ik_tests, p.seconds);
}
