// Tests of cpp/sensing: force–torque filter chain, elevation sampling and hole filling,
// observation layout and scaling, path and reward (seed 004 §4.2–4.3).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <set>
#include <stdexcept>
#include <string>

#include "test_util.hpp"
#include "ernest/sensing/elevation_sampler.hpp"
#include "ernest/sensing/fts_processor.hpp"
#include "ernest/sensing/observation.hpp"
#include "ernest/sensing/path_reward.hpp"

using namespace ernest::sensing;
using ernest::testing::invalid_argument_message;

namespace {

// Plane z = z0 + gx x + gy y, optionally with a hole (no data) where hole(x, y) is true.
struct PlaneSource : HeightSource {
  double z0 = 0, gx = 0, gy = 0;
  std::function<bool(double, double)> hole = [](double, double) { return false; };
  bool height(double x, double y, double& z) const override {
    if (hole(x, y)) return false;
    z = z0 + gx * x + gy * y;
    return true;
  }
};

Eigen::Matrix3d rot_zyx(double yaw, double pitch, double roll) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}
}  // namespace

TEST(Fts, StepResponseHasTheHalfHertzTimeConstant) {
  // Continuous first-order low-pass: y(t) = 1 - exp(-t / tau), tau = 1 / (2 pi 0.5 Hz) = 0.318 s.
  FtsProcessor p;  // 400 Hz, 0.5 Hz
  p.reset(Wrenches::Zero());
  const double tau = 1.0 / (2.0 * M_PI * 0.5);
  for (int k = 1; k <= 800; ++k) {
    p.update(Wrenches::Ones());
    const double t = k / 400.0;
    ASSERT_NEAR(p.filtered()(2, 3), 1.0 - std::exp(-t / tau), 1e-12) << "sample " << k;
  }
  // After one time constant (127.3 samples) the response has crossed 63.2 %.
  FtsProcessor q;
  q.reset(Wrenches::Zero());
  int k = 0;
  while (q.filtered()(0, 0) < 1.0 - std::exp(-1.0)) q.update(Wrenches::Ones()), ++k;
  EXPECT_EQ(k, 128);
}

TEST(Fts, BiasAndFourSensorMeanAreRemoved) {
  FtsProcessor p;
  Wrenches w;
  for (int i = 0; i < 4; ++i)
    for (int a = 0; a < 6; ++a) w(i, a) = 10.0 * i + a;
  p.reset(w);
  EXPECT_NEAR(p.processed().colwise().sum().cwiseAbs().maxCoeff(), 0.0, 1e-12);
  p.set_bias(w);  // calibrated at this very reading: everything vanishes
  EXPECT_NEAR(p.processed().cwiseAbs().maxCoeff(), 0.0, 1e-12);
  // A drift common to all four sensors is invisible after mean removal (§4.2).
  Wrenches drift = w;
  drift.rowwise() += Eigen::Matrix<double, 1, 6>::Constant(7.5);
  p.reset(drift);
  EXPECT_NEAR(p.processed().cwiseAbs().maxCoeff(), 0.0, 1e-12);
  Wrenches bad = w;
  bad(1, 2) = NAN;
  EXPECT_THROW(p.update(bad), std::invalid_argument);
  FtsFilterOptions o;
  o.cutoff = 300.0;  // above Nyquist of 400 Hz
  EXPECT_NE(invalid_argument_message([&] { FtsProcessor{o}; }).find("cutoff"), std::string::npos);
}

TEST(Elevation, FlatGroundAtRestGivesZerosForAnyHeightSlopeAndYaw) {
  ElevationSampler s;
  const double ground_z = s.options().ground_z;
  for (double yaw : {0.0, 0.7, -2.5}) {
    for (double slope : {0.0, 0.2, -0.35}) {
      // Ground plane through the origin tilted by `slope` about the chassis y axis; the chassis
      // rests on it, parallel, with its origin -ground_z above it along its own z axis.
      const Eigen::Matrix3d R = rot_zyx(yaw, slope, 0.1);
      const Eigen::Vector3d n = R.col(2);
      const Eigen::Vector3d base(3.0, -2.0, 100.0);
      PlaneSource plane;
      plane.gx = -n.x() / n.z();
      plane.gy = -n.y() / n.z();
      plane.z0 = base.z() - plane.gx * base.x() - plane.gy * base.y();
      const Eigen::Vector3d position = base - ground_z * n;
      const ElevationSample e = s.sample(position, R, plane);
      EXPECT_NEAR(e.values.cwiseAbs().maxCoeff(), 0.0, 1e-9) << yaw << " " << slope;
      for (int k : e.source) EXPECT_EQ(k, 0);
    }
  }
}

TEST(Elevation, StepAheadIsSeenOnlyByTheFarPoints) {
  ElevationSampler s;
  struct Step : HeightSource {
    bool height(double x, double, double& z) const override {
      z = x > 1.0 ? 0.25 : 0.0;
      return true;
    }
  } step;
  const Eigen::Vector3d pos(0.0, 0.0, -s.options().ground_z);
  const ElevationSample e = s.sample(pos, Eigen::Matrix3d::Identity(), step);
  // Front wheels at x = 0.43: points at 0.63, 0.83, 1.03 -> only the third sees the step.
  EXPECT_NEAR(e.values[0], 0.0, 1e-12);
  EXPECT_NEAR(e.values[1], 0.0, 1e-12);
  EXPECT_NEAR(e.values[2], 0.25, 1e-12);
  EXPECT_NEAR(e.values[5], 0.25, 1e-12);
  // Rear wheels at x = -0.43: points at -0.23, -0.03, 0.17 -> flat.
  EXPECT_NEAR(e.values.segment<6>(6).cwiseAbs().maxCoeff(), 0.0, 1e-12);
}

TEST(Elevation, HolesAreFilledLinearlyAlongTheSamplingDirection) {
  ElevationSampler s;
  PlaneSource ramp;
  ramp.gx = 0.1;  // linear terrain: linear interpolation across a hole must be exact
  ramp.hole = [](double x, double) { return std::abs(x - 0.75) < 0.2; };
  const Eigen::Vector3d pos(0.0, 0.0, -s.options().ground_z);
  const ElevationSample e = s.sample(pos, Eigen::Matrix3d::Identity(), ramp);
  for (int k = 0; k < kElevationSamples; ++k) {
    const Eigen::Vector2d p = s.point(k);
    EXPECT_NEAR(e.values[k], 0.1 * p.x(), 1e-9) << "sample " << k;
  }
  EXPECT_EQ(e.source[0], 1);  // x = 0.63 lies in the hole: interpolated
  EXPECT_EQ(e.source[2], 0);  // x = 1.03: measured
  // A hole reaching beyond the search range ahead: held at the last valid value behind.
  PlaneSource open_ahead = ramp;
  open_ahead.hole = [](double x, double) { return x > 0.5; };
  const ElevationSample h = s.sample(pos, Eigen::Matrix3d::Identity(), open_ahead);
  EXPECT_EQ(h.source[2], 2);
  EXPECT_NEAR(h.values[2], 0.1 * 0.5, 0.1 * 0.05 + 1e-9);  // nearest valid within one step
  // No data anywhere: nominal ground (0), flagged.
  PlaneSource none;
  none.hole = [](double, double) { return true; };
  const ElevationSample z = s.sample(pos, Eigen::Matrix3d::Identity(), none);
  EXPECT_EQ(z.values.cwiseAbs().maxCoeff(), 0.0);
  for (int k : z.source) EXPECT_EQ(k, 3);
}

TEST(Elevation, FillLineInterpolatesAndHoldsAtTheEnds) {
  Eigen::VectorXd s(6), v(6);
  s << 0, 1, 2, 3, 4, 5;
  v << 99, 1.0, 99, 99, 4.0, 99;
  Eigen::Array<bool, Eigen::Dynamic, 1> ok(6);
  ok << false, true, false, false, true, false;
  EXPECT_TRUE(fill_line(s, v, ok));
  EXPECT_DOUBLE_EQ(v[0], 1.0);
  EXPECT_DOUBLE_EQ(v[2], 2.0);
  EXPECT_DOUBLE_EQ(v[3], 3.0);
  EXPECT_DOUBLE_EQ(v[5], 4.0);
  ok.setConstant(false);
  EXPECT_FALSE(fill_line(s, v, ok));
}

TEST(Observation, LayoutScalingAndNames) {
  const std::vector<std::string> names = observation_names();
  ASSERT_EQ(names.size(), 45u);
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), 45u);
  EXPECT_EQ(names[kFtsBegin + 6 * 1 + 2], "fts_FR_Fz");
  EXPECT_EQ(names[kElevationBegin + 11], "elev_RR_2");
  EXPECT_EQ(names[kActionBegin], "action_vx");
  ObservationInputs in;
  in.heading_deviation = M_PI / 2;
  in.lateral_deviation = -1.0;
  in.fts(1, 2) = 100.0;   // FR Fz
  in.fts(3, 5) = -20.0;   // RR Tz
  in.elevation[4] = 0.25;
  in.action << 1.0, -0.5, 0.25;
  const ObservationVector o = build_observation(in);
  EXPECT_DOUBLE_EQ(o[kHeadingDeviation], 0.5);
  EXPECT_DOUBLE_EQ(o[kLateralDeviation], -0.5);
  EXPECT_DOUBLE_EQ(o[kFtsBegin + 6 + 2], 0.5);
  EXPECT_DOUBLE_EQ(o[kFtsBegin + 18 + 5], -0.5);
  EXPECT_DOUBLE_EQ(o[kElevationBegin + 4], 0.5);
  EXPECT_DOUBLE_EQ(o[kActionBegin + 1], -0.5);
  in.elevation[5] = 100.0;  // absurd: clipped to ten times the maximum expected value
  EXPECT_DOUBLE_EQ(build_observation(in)[kElevationBegin + 5], kObservationClip);
  in.elevation[7] = NAN;
  EXPECT_NE(invalid_argument_message([&] { build_observation(in); }).find("elev_RL_1"), std::string::npos);
}

TEST(Observation, ActionMappingMatchesSection42) {
  const ActionLimits lim;
  EXPECT_TRUE(action_to_command({-1, 0, 0}, lim).isApprox(Eigen::Vector3d(0, 0, 0)));
  const Eigen::Vector3d full = action_to_command({1, 1, -1}, lim);
  EXPECT_DOUBLE_EQ(full[0], 0.2);
  EXPECT_NEAR(full[1], 20.0 * M_PI / 180, 1e-9);
  EXPECT_NEAR(full[2], -10.0 * M_PI / 180, 1e-9);
  const Eigen::Vector3d clamped = action_to_command({3, -7, 0}, lim);
  EXPECT_DOUBLE_EQ(clamped[0], 0.2);
  EXPECT_NEAR(clamped[1], -20.0 * M_PI / 180, 1e-9);
  const ActionVector a(0.3, -0.2, 0.9);
  EXPECT_TRUE(command_to_action(action_to_command(a, lim), lim).isApprox(a, 1e-12));
  EXPECT_THROW(action_to_command({NAN, 0, 0}, lim), std::invalid_argument);
}

TEST(PathReward, Equations33To38) {
  PathLine path{1.0, 2.0, 0.0};
  EXPECT_DOUBLE_EQ(path.lateral_deviation(5.0, 2.0), 0.0);
  EXPECT_DOUBLE_EQ(path.lateral_deviation(5.0, 3.5), 1.5);  // positive to the left
  // 0.1 m/s along the path for one 0.5 s policy step: 0.05 m of progress, reward 2 * 0.05 / 0.5.
  RewardTerms t = compute_reward(path, 1.0, 2.0, 1.05, 2.0, 0.0);
  EXPECT_NEAR(t.progress, 0.05, 1e-15);
  EXPECT_NEAR(t.reward, 0.2, 1e-15);
  // Lateral and torque penalties.
  t = compute_reward(path, 1.0, 3.0, 1.0, 3.0, -50.0);
  EXPECT_NEAR(t.lateral_term, -0.1, 1e-15);
  EXPECT_NEAR(t.torque_term, -0.005, 1e-15);
  EXPECT_NEAR(t.reward, -0.105, 1e-15);
  // Rotation invariance: the same motion along a path at 37 deg gives the same terms.
  const double th = 37.0 * M_PI / 180;
  PathLine rotated{0.0, 0.0, th};
  const RewardTerms r = compute_reward(rotated, 0.0, 0.0, 0.05 * std::cos(th) - 0.3 * std::sin(th),
                                       0.05 * std::sin(th) + 0.3 * std::cos(th), 0.0);
  EXPECT_NEAR(r.progress, 0.05, 1e-12);
  EXPECT_NEAR(r.lateral, 0.3, 1e-12);
  EXPECT_NEAR(rotated.heading_deviation(th + 2 * M_PI + 0.1), 0.1, 1e-12);
  EXPECT_NEAR(rotated.heading_deviation(th + M_PI), M_PI, 1e-12);
  EXPECT_THROW(compute_reward(path, 0, 0, NAN, 0, 0), std::invalid_argument);
}
