// Tests of cpp/envs: Perlin noise and the seed 004 §4.5 / Table 3 scenario generators.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "ernest/envs/perlin.hpp"
#include "ernest/envs/scenarios.hpp"

using namespace ernest::envs;

namespace {
constexpr double kDeg = M_PI / 180.0;
Scenario make(ScenarioKind k, std::uint64_t seed, double noise_unit = 0.1) {
  ScenarioOptions o;
  o.kind = k;
  o.noise_unit = noise_unit;
  return generate_scenario(o, seed);
}
// Rover yaw offset from the path heading, wrapped.
double yaw_offset(const Scenario& s) { return s.path.heading_deviation(s.start_heading); }
}  // namespace

TEST(Perlin, DeterministicBoundedZeroOnLatticeAndContinuous) {
  PerlinNoise a(1), b(1), c(2);
  double max_abs = 0, max_step = 0, diff = 0;
  for (int i = 0; i < 4000; ++i) {
    const double x = 0.013 * i, y = 0.7 + 0.0071 * i;
    EXPECT_EQ(a(x, y), b(x, y));
    max_abs = std::max(max_abs, std::abs(a(x, y)));
    max_step = std::max(max_step, std::abs(a(x + 1e-4, y) - a(x, y)));
    diff = std::max(diff, std::abs(a(x, y) - c(x, y)));
  }
  EXPECT_LE(max_abs, 1.0);
  EXPECT_GT(max_abs, 0.2);     // not degenerate
  EXPECT_LT(max_step, 1e-3);   // gradient bounded: continuous
  EXPECT_GT(diff, 0.1);        // seeds matter
  for (int i = -3; i < 4; ++i) EXPECT_EQ(a(i, 2 * i), 0.0);
  const TerrainNoise n(5, 0.05);
  for (int i = 0; i < 1000; ++i) EXPECT_LE(std::abs(n(0.37 * i, 0.11 * i)), 1.5 * 0.05);
}

TEST(Scenarios, SameSeedSameTerrainDifferentSeedDifferent) {
  for (const std::string& name : scenario_names()) {
    ScenarioOptions o;
    o.kind = scenario_kind(name);
    const Scenario a = generate_scenario(o, 42), b = generate_scenario(o, 42);
    EXPECT_EQ(a.terrain.heights(), b.terrain.heights()) << name;
    ASSERT_EQ(a.obstacles.size(), b.obstacles.size()) << name;
    for (size_t i = 0; i < a.obstacles.size(); ++i) {
      EXPECT_EQ(a.obstacles[i].centre, b.obstacles[i].centre);
    }
    EXPECT_EQ(a.start_heading, b.start_heading);
    EXPECT_TRUE(a.terrain.heights().allFinite()) << name;
  }
  EXPECT_NE(make(ScenarioKind::Ripples, 1).terrain.heights(),
            make(ScenarioKind::Ripples, 2).terrain.heights());
  EXPECT_THROW(scenario_kind("moon"), std::invalid_argument);
}

TEST(Scenarios, RockFieldWithinTable3AndRocksOnTheSurface) {
  double rocks = 0, area_density = 0;
  for (std::uint64_t seed = 0; seed < 150; ++seed) {
    const Scenario s = make(ScenarioKind::RockField, seed);
    EXPECT_LE(std::abs(s.ground_pitch), 5 * kDeg);
    EXPECT_LE(std::abs(s.ground_roll), 5 * kDeg);
    EXPECT_GE(s.rock_density, 0.0);
    EXPECT_LE(s.rock_density, 0.5);
    EXPECT_LE(std::abs(yaw_offset(s)), 180 * kDeg + 1e-12);
    EXPECT_LE(std::abs(s.path.lateral_deviation(s.start_x, s.start_y)), 2.0 + 1e-12);
    EXPECT_GE(s.friction, 0.5);
    EXPECT_LE(s.friction, 0.9);
    EXPECT_DOUBLE_EQ(s.episode_duration, 60.0);
    for (const auto& b : s.obstacles) {
      EXPECT_GE(b.size.x(), 0.2);
      EXPECT_LE(b.size.x(), 0.4);
      EXPECT_GE(b.size.y(), 0.2);
      EXPECT_LE(b.size.y(), 0.6);
      EXPECT_GE(b.size.z(), 0.2);
      EXPECT_LE(b.size.z(), 0.6);
      EXPECT_LE(std::abs(b.yaw), 90 * kDeg);
      EXPECT_LE(std::abs(b.pitch), 20 * kDeg);
      EXPECT_LE(std::abs(b.roll), 20 * kDeg);
      // §4.5.1: centres lie on the terrain surface.
      EXPECT_NEAR(b.centre.z(), s.terrain.height(b.centre.x(), b.centre.y()), 1e-12);
      EXPECT_GE(std::hypot(b.centre.x() - s.start_x, b.centre.y() - s.start_y), 1.2);
    }
    rocks += s.obstacles.size();
    const double area = (s.terrain.length_x() - 1.0) * (s.terrain.length_y() - 1.0);
    area_density += s.rock_density * area;
  }
  // The placement scheme must give the sampled mean density: expected rock count = sum rho * area
  // (minus the cleared start zone, ~4.5 m^2 of ~230 m^2). Poisson-binomial spread: within 8 %.
  EXPECT_NEAR(rocks / area_density, 1.0, 0.08);
}

TEST(Scenarios, StepWithinTable3) {
  for (std::uint64_t seed = 0; seed < 200; ++seed) {
    const Scenario s = make(ScenarioKind::Step, seed);
    EXPECT_GE(s.step_height, 0.2);
    EXPECT_LE(s.step_height, 0.3);
    EXPECT_GE(s.step_distance, 1.2);
    EXPECT_LE(s.step_distance, 1.6);
    EXPECT_LE(std::abs(s.step_yaw), 20 * kDeg);
    EXPECT_LE(std::abs(yaw_offset(s)), 45 * kDeg);
    EXPECT_LE(std::abs(s.path.lateral_deviation(0, 0)), 1.0 + 1e-12);
    EXPECT_DOUBLE_EQ(s.episode_duration, 30.0);
    ASSERT_EQ(s.obstacles.size(), 1u);
    const auto& b = s.obstacles[0];
    // The face is step_distance ahead of the start along the rover heading, the top step_height
    // above the ground there.
    const double dir = s.start_heading + s.step_yaw;
    const Eigen::Vector2d face(b.centre.x() - 0.5 * b.size.x() * std::cos(dir),
                               b.centre.y() - 0.5 * b.size.x() * std::sin(dir));
    EXPECT_NEAR(face.x(), s.step_distance * std::cos(s.start_heading), 1e-9);
    EXPECT_NEAR(face.y(), s.step_distance * std::sin(s.start_heading), 1e-9);
    const double ground = s.terrain.height(face.x(), face.y());
    EXPECT_NEAR(b.centre.z() + 0.5 * b.size.z(), ground + s.step_height, 1e-9);
    EXPECT_GT(b.size.y(), 20.0);  // effectively infinite
  }
}

TEST(Scenarios, RipplesFollowEquation39WithinTable3) {
  for (std::uint64_t seed = 0; seed < 100; ++seed) {
    const Scenario s = make(ScenarioKind::Ripples, seed, 0.0);  // no noise: exact profile
    ASSERT_EQ(s.ripples.size(), 4u);
    EXPECT_LE(std::abs(s.path.heading), 20 * kDeg);
    EXPECT_LE(std::abs(yaw_offset(s)), 45 * kDeg);
    for (size_t i = 0; i < 4; ++i) {
      const RippleSpec& r = s.ripples[i];
      EXPECT_GE(r.amplitude, 0.1);
      EXPECT_LE(r.amplitude, 0.3);
      EXPECT_GE(r.wavelength, 0.6);
      EXPECT_LE(r.wavelength, 1.0);
      EXPECT_GE(r.alpha, 0.0);
      EXPECT_LE(r.alpha, 0.2);
      if (i > 0) EXPECT_NEAR(r.start, s.ripples[i - 1].start + s.ripples[i - 1].wavelength, 1e-12);
    }
    // At the grid nodes the map is eq 39 exactly (one period per ripple, trough to trough); the
    // highest node of each ripple is within one grid step of the crest height A.
    const auto& H = s.terrain.heights();
    const int j = static_cast<int>(H.cols() / 2);
    for (Eigen::Index i = 0; i < H.rows(); ++i) {
      const double x = s.terrain.origin_x() + i * s.terrain.spacing();
      double expected = 0.0;
      for (const RippleSpec& r : s.ripples) {
        if (x >= r.start && x < r.start + r.wavelength) {
          expected = ripple_height(x - r.start - 0.25 * r.wavelength, r.amplitude, r.wavelength,
                                   r.alpha);
        }
      }
      ASSERT_NEAR(H(i, j), expected, 1e-12) << "x = " << x;
    }
    for (const RippleSpec& r : s.ripples) {
      double top = 0;
      for (Eigen::Index i = 0; i < H.rows(); ++i) {
        const double x = s.terrain.origin_x() + i * s.terrain.spacing();
        if (x >= r.start && x < r.start + r.wavelength) top = std::max(top, H(i, j));
      }
      EXPECT_LE(top, r.amplitude + 1e-12);
      EXPECT_GE(top, r.amplitude * (1 - 4 * s.terrain.spacing() / r.wavelength));
    }
  }
}

TEST(Ripples, TriangularAndSinusoidalLimits) {
  // alpha = 0: a triangular wave between 0 and A (linear flanks).
  const double A = 0.3, L = 0.8;
  for (double x = -0.2; x <= 0.2; x += 0.01) {
    EXPECT_NEAR(ripple_height(x, A, L, 0.0), A / 2 + A * x / (L / 2), 1e-12);
  }
  // alpha -> 1: tends to A/2 (1 + sin(2 pi x / lambda)); error O((1 - alpha)^2).
  for (double x = 0; x < L; x += 0.01) {
    EXPECT_NEAR(ripple_height(x, A, L, 0.99), A / 2 * (1 + std::sin(2 * M_PI * x / L)), 1e-4 * A);
  }
  EXPECT_THROW(ripple_height(0.1, A, L, 1.0), std::invalid_argument);
}

TEST(Scenarios, SlopesHaveTheSampledAngle) {
  int direct = 0, full = 0;
  for (std::uint64_t seed = 0; seed < 200; ++seed) {
    const Scenario s = make(ScenarioKind::Slope, seed, 0.0);
    EXPECT_GE(s.slope_angle, 15 * kDeg);
    EXPECT_LE(s.slope_angle, 30 * kDeg);
    EXPECT_GE(s.slope_beta_start, 0.1);
    EXPECT_LE(s.slope_beta_start, 0.5);
    EXPECT_GE(s.slope_beta_end, 0.2);
    EXPECT_LE(s.slope_beta_end, 2.0);
    EXPECT_GE(s.slope_length, 1.5);
    EXPECT_LE(s.slope_length, 3.0);
    EXPECT_LE(std::abs(s.path.heading), 20 * kDeg);
    // The map equals the §4.5.4 profile at its nodes...
    const auto& H = s.terrain.heights();
    const int j = static_cast<int>(H.cols() / 2);
    for (Eigen::Index i = 0; i < H.rows(); ++i) {
      const double x = s.terrain.origin_x() + i * s.terrain.spacing();
      ASSERT_NEAR(H(i, j), slope_height(x, s.slope_start, s.slope_angle, s.slope_beta_start,
                                        s.slope_beta_end, s.slope_length), 1e-12);
    }
    // ...whose steepest gradient (fine central differences) is the reported peak...
    double g = 0;
    for (double u = 0; u < 8; u += 1e-3) {
      const double d = (slope_height(u + 1e-7, s.slope_start, s.slope_angle, s.slope_beta_start,
                                     s.slope_beta_end, s.slope_length) -
                        slope_height(u - 1e-7, s.slope_start, s.slope_angle, s.slope_beta_start,
                                     s.slope_beta_end, s.slope_length)) / 2e-7;
      g = std::max(g, d);
    }
    EXPECT_NEAR(g, s.peak_slope, 2e-3 * s.peak_slope);
    if (s.slope_direct) {
      ++direct;
      EXPECT_LT(s.peak_slope, std::tan(s.slope_angle));
    } else {
      ++full;
      EXPECT_NEAR(s.peak_slope, std::tan(s.slope_angle), 1e-12);
      // ...and the constant-slope section of the map rises at exactly tan(angle).
      const double a = std::tan(s.slope_angle) / (2 * s.slope_beta_start);
      const double b = std::tan(s.slope_angle) / (2 * s.slope_beta_end);
      if (s.slope_length - a - b > 0.2) {
        const double u0 = s.slope_start + a + 0.05;
        EXPECT_NEAR((s.terrain.height(u0 + 0.1, 0) - s.terrain.height(u0, 0)) / 0.1,
                    std::tan(s.slope_angle), 1e-9);
      }
    }
    // The profile's length is the sampled one: flat again after start + length.
    const double top = s.terrain.height(s.slope_start + s.slope_length + 0.3, 0.0);
    EXPECT_NEAR(s.terrain.height(s.slope_start + s.slope_length + 1.5, 0.0), top, 1e-9);
  }
  EXPECT_GT(direct, 10);
  EXPECT_GT(full, 10);
}

TEST(Scenarios, EvaluationSlopeSpreadDrawsTheAnglePerSeed) {
  ScenarioOptions o;
  o.kind = ScenarioKind::SlopeEval;
  o.eval_slope_spread_deg = 0.5;
  double lo = 90.0, hi = 0.0;
  for (std::uint64_t seed = 0; seed < 40; ++seed) {
    const Scenario s = generate_scenario(o, seed);
    const double deg = std::atan(s.peak_slope) / kDeg;
    EXPECT_NEAR(s.slope_angle / kDeg, deg, 1e-9);
    EXPECT_LE(std::abs(deg - 20.0), 0.5 + 1e-12);
    lo = std::min(lo, deg);
    hi = std::max(hi, deg);
    EXPECT_EQ(generate_scenario(o, seed).slope_angle, s.slope_angle);  // same seed, same course
  }
  EXPECT_GT(hi - lo, 0.6);  // 40 uniform draws over 1 deg cover most of it
  o.eval_slope_spread_deg = 0.0;
  EXPECT_NEAR(std::atan(generate_scenario(o, 7).peak_slope), 20 * kDeg, 1e-12);
  o.eval_slope_spread_deg = 25.0;  // would leave [0, 45] deg
  EXPECT_THROW(generate_scenario(o, 0), std::invalid_argument);
  o.eval_slope_spread_deg = -1.0;
  EXPECT_THROW(generate_scenario(o, 0), std::invalid_argument);
}

TEST(Scenarios, EvaluationCourses) {
  const Scenario slope = make(ScenarioKind::SlopeEval, 0);
  EXPECT_NEAR(std::atan(slope.peak_slope), 20 * kDeg, 1e-12);
  EXPECT_FALSE(slope.slope_direct);
  EXPECT_NEAR((slope.terrain.height(6.0, 0) - slope.terrain.height(5.0, 0)), std::tan(20 * kDeg), 1e-9);
  // the whole rover (wheelbase 0.86 m around x = 0) starts on the constant slope
  EXPECT_NEAR((slope.terrain.height(0.5, 0) - slope.terrain.height(-0.5, 0)), std::tan(20 * kDeg), 1e-9);
  const Scenario step = make(ScenarioKind::WheelStep, 0);
  EXPECT_DOUBLE_EQ(step.step_height, 0.34);  // wheel diameter (Table 1)
  // §5.2's trap as chosen by benchmarks/bench_bickler_scan.py: a 0.09 m row, 0.3 m deep.
  const Scenario trap = make(ScenarioKind::BicklerTrap, 0);
  ASSERT_EQ(trap.obstacles.size(), 6u);
  for (const auto& b : trap.obstacles) {
    EXPECT_DOUBLE_EQ(b.size.x(), 0.3);  // shorter than the 0.86 m wheelbase: straddled
    EXPECT_NEAR(b.centre.z() + 0.5 * b.size.z(), 0.09, 0.005 + 1e-12);
  }
  EXPECT_GE(trap.friction, 0.5);  // drawn from Table 3 unless fixed
  EXPECT_LE(trap.friction, 0.9);
  const Scenario course = make(ScenarioKind::Course, 0);
  EXPECT_EQ(course.ripples.size(), 3u);
  EXPECT_GT(course.obstacles.size(), 5u);
  EXPECT_DOUBLE_EQ(course.episode_duration, 180.0);
}

TEST(Scenarios, RandomisationRangesAreOptions) {
  // range_scale 0: nominal trials (no tilt, yaw, lateral or heading offset); intervals overridden.
  ScenarioOptions o;
  o.range_scale = 0.0;
  for (ScenarioKind k : {ScenarioKind::RockField, ScenarioKind::Slope, ScenarioKind::Ripples}) {
    o.kind = k;
    for (std::uint64_t seed = 0; seed < 20; ++seed) {
      const Scenario s = generate_scenario(o, seed);
      EXPECT_EQ(s.ground_pitch, 0.0);
      EXPECT_EQ(s.path.heading, 0.0);
      EXPECT_EQ(yaw_offset(s), 0.0);
      EXPECT_EQ(s.path.lateral_deviation(0, 0), 0.0);
    }
  }
  ScenarioOptions h;
  h.kind = ScenarioKind::Step;
  h.step_height_range = {0.1, 0.12};
  h.range_scale = 0.5;
  for (std::uint64_t seed = 0; seed < 50; ++seed) {
    const Scenario s = generate_scenario(h, seed);
    EXPECT_GE(s.step_height, 0.1);
    EXPECT_LE(s.step_height, 0.12);
    EXPECT_LE(std::abs(yaw_offset(s)), 22.5 * kDeg + 1e-12);  // half of Table 3's 45 deg
  }
  ScenarioOptions sl;
  sl.kind = ScenarioKind::Slope;
  sl.slope_angle_range_deg = {10.0, 10.0};
  EXPECT_NEAR(generate_scenario(sl, 3).slope_angle, 10.0 * kDeg, 1e-15);
  ScenarioOptions bt;  // the Bickler trap's row and the obstacle friction are options
  bt.kind = ScenarioKind::BicklerTrap;
  bt.bickler_height = 0.2;
  bt.bickler_depth = 0.45;
  bt.obstacle_friction = 0.6;
  const Scenario trap = generate_scenario(bt, 4);
  for (const auto& b : trap.obstacles) {
    EXPECT_DOUBLE_EQ(b.size.x(), 0.45);
    EXPECT_NEAR(b.centre.z() + 0.5 * b.size.z(), 0.2, 0.005 + 1e-12);
  }
  EXPECT_EQ(trap.friction, 0.6);
  bt.obstacle_friction = std::nullopt;  // drawn again, as without the option (the same draws)
  bt.kind = ScenarioKind::RockField;
  ScenarioOptions rf;
  EXPECT_EQ(generate_scenario(bt, 4).friction, generate_scenario(rf, 4).friction);
  bt.obstacle_friction = 0.8;
  const Scenario fixed = generate_scenario(bt, 4), drawn = generate_scenario(rf, 4);
  EXPECT_EQ(fixed.friction, 0.8);
  ASSERT_EQ(fixed.obstacles.size(), drawn.obstacles.size());  // fixing it moves no rock
  for (size_t i = 0; i < fixed.obstacles.size(); ++i)
    EXPECT_EQ(fixed.obstacles[i].centre, drawn.obstacles[i].centre);
  const auto message = [](const ScenarioOptions& b) {
    try {
      generate_scenario(b, 0);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  for (auto field : {&ScenarioOptions::bickler_height, &ScenarioOptions::bickler_depth}) {
    ScenarioOptions b;
    b.*field = 3.0;  // out of range for each: the message names the field
    const std::string name = field == &ScenarioOptions::bickler_height ? "bickler_height" : "bickler_depth";
    EXPECT_NE(message(b).find("ScenarioOptions." + name), std::string::npos) << message(b);
  }
  // A set obstacle friction is a real one: no 0 or negative "draw it" sentinel, no NaN.
  for (double mu : {3.0, 0.0, -1.0, std::nan("")}) {
    ScenarioOptions b;
    b.obstacle_friction = mu;
    EXPECT_NE(message(b).find("ScenarioOptions.obstacle_friction"), std::string::npos) << mu;
  }
  ScenarioOptions deep;
  deep.bickler_depth = 0.86;  // as deep as the wheelbase: it could not be straddled
  EXPECT_THROW(generate_scenario(deep, 0), std::invalid_argument);
  ScenarioOptions bad;
  bad.step_height_range = {0.3, 0.2};
  EXPECT_THROW(generate_scenario(bad, 0), std::invalid_argument);
  bad = ScenarioOptions{};
  bad.range_scale = 2.0;
  EXPECT_THROW(generate_scenario(bad, 0), std::invalid_argument);
}
