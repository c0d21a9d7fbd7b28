// Tests of cpp/soil against the paper's equations and independent facts.
#include <gtest/gtest.h>

#include <cmath>

#include "ernest/soil/bekker_wong.hpp"
#include "ernest/soil/single_wheel.hpp"

using namespace ernest::soil;

TEST(BekkerWong, NoForceAboveGround) {
  const BekkerWongModel m(SoilParameters::m90(), WheelGeometry{});
  for (double h : {0.0, -0.01, -1.0}) {
    const WheelSoilForce f = m.evaluate({h, 0.1, 0.05, -0.05, 0.05});
    EXPECT_EQ(f.fx, 0.0);
    EXPECT_EQ(f.fy, 0.0);
    EXPECT_EQ(f.fz, 0.0);
    EXPECT_EQ(f.axle_torque, 0.0);
  }
}
