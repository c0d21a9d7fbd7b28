// Self-collision of the walker with FCL (seed 003 §3.4): the standard stances are free, legs
// yawed into each other collide, and FCL's capsule distances agree with a brute-force sampling
// of the two segments.
#include <gtest/gtest.h>

#include <cmath>

#include "ernest/walker/self_collision.hpp"
#include "test_util.hpp"

using namespace ernest::walker;
using ernest::testing::invalid_argument_message;

namespace {

constexpr double kPi = 3.14159265358979323846;

// min over sampled points of |a(s) − b(t)| − ra − rb, clamped at 0 (independent of FCL).
double sampled_distance(const LinkCapsule& a, const LinkCapsule& b) {
  double best = HUGE_VAL;
  const int n = 400;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const Eigen::Vector3d pa = a.p0 + (a.p1 - a.p0) * (double(i) / n);
      const Eigen::Vector3d pb = b.p0 + (b.p1 - b.p0) * (double(j) / n);
      best = std::min(best, (pa - pb).norm());
    }
  return std::max(0.0, best - a.radius - b.radius);
}

const LinkCapsule& find(const std::vector<LinkCapsule>& caps, int link) {
  for (const auto& c : caps)
    if (c.link == link) return c;
  throw std::runtime_error("no such link");
}

}  // namespace

TEST(WalkerCollision, StandardStancesAreFree) {
  for (const auto& params : {sdm_b_parameters(), t12_parameters()}) {
    const WalkerModel m(params);
    EXPECT_TRUE(self_collisions(m, m.standard_configuration()).empty()) << params.name;
  }
}

TEST(WalkerCollision, LegsYawedIntoEachOtherCollide) {
  const WalkerModel m(sdm_b_parameters());
  Eigen::MatrixXd q = m.standard_configuration();
  q(0, 0) = 50 * kPi / 180;   // leg 0 towards leg 1 ...
  q(0, 1) = -50 * kPi / 180;  // ... and leg 1 towards leg 0
  const auto pairs = self_collisions(m, q);
  ASSERT_FALSE(pairs.empty());
  for (const auto& p : pairs) {
    EXPECT_EQ(p.leg_a, 0);
    EXPECT_EQ(p.leg_b, 1);
    EXPECT_EQ(p.distance, 0.0);
  }
  // The wheels meet: their axle capsules (radius = wheel radius) overlap.
  EXPECT_TRUE(std::any_of(pairs.begin(), pairs.end(), [](auto& p) { return p.link_a == -1 && p.link_b == -1; }));
}

TEST(WalkerCollision, DistancesMatchSampledCapsules) {
  const WalkerModel m(sdm_b_parameters());
  Eigen::MatrixXd q = m.standard_configuration();
  q(0, 0) = 30 * kPi / 180;
  q(0, 1) = -20 * kPi / 180;
  const auto near = self_collisions(m, q, 0.6);
  const auto touching = self_collisions(m, q, 0.0);
  EXPECT_GE(near.size(), touching.size());
  int compared = 0;
  for (const auto& p : near) {
    EXPECT_LE(p.distance, 0.6);
    if (p.leg_b == kChassis) continue;
    const double expected = sampled_distance(find(m.leg_capsules(p.leg_a, q.col(p.leg_a)), p.link_a),
                                             find(m.leg_capsules(p.leg_b, q.col(p.leg_b)), p.link_b));
    EXPECT_NEAR(p.distance, expected, 3e-3) << p.leg_a << ":" << p.link_a << " " << p.leg_b << ":" << p.link_b;
    ++compared;
  }
  EXPECT_GT(compared, 0);
  EXPECT_NE(invalid_argument_message([&] { self_collisions(m, q, -1.0); }).find("clearance"), std::string::npos);
}
