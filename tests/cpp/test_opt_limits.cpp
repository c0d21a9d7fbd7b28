// Exact joint limits of the gait transitions (seed 000 eqs 16–17): the limits are
// imposed and reported at the analytic extrema of each cubic segment, so no transition exceeds them
// between samples.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "ernest/opt/transition.hpp"

using namespace ernest::opt;

namespace {

// Normalised violation max(|q| / P - 1, |q̇| / V - 1) over joints from 2001 uniform samples.
double dense_violation(const TransitionProblem& pb, const TransitionResult& r, int samples = 2000) {
  double worst = -HUGE_VAL;
  for (int j = 0; j < pb.joints(); ++j)
    for (int k = 0; k <= samples; ++k) {
      double q, dq, ddq;
      r.evaluate(j, r.duration * k / samples, q, dq, ddq);
      worst = std::max({worst, std::abs(q) / pb.position_limit[j] - 1.0,
                        std::abs(dq) / pb.velocity_limit[j] - 1.0});
    }
  return worst;
}

// The same from TransitionResult::peaks (the analytic extrema).
double analytic_violation(const TransitionProblem& pb, const TransitionResult& r) {
  double worst = -HUGE_VAL;
  for (int j = 0; j < pb.joints(); ++j) {
    double q, v;
    r.peaks(j, q, v);
    worst = std::max({worst, q / pb.position_limit[j] - 1.0, v / pb.velocity_limit[j] - 1.0});
  }
  return worst;
}

}  // namespace

TEST(ExactLimits, CubicExtremaFindsTheStationaryPoints) {
  // q(u) = (u - 0.2)(u - 0.7)(u - 1.5): q'(u) = 3u^2 - 4.8u + 1.69, q''(u) = 6u - 4.8.
  const CubicExtrema e = cubic_extrema(1.69, -4.8, 1.2);
  ASSERT_EQ(e.roots, 1);  // the second root of q', (4.8 + sqrt(2.76)) / 6 = 1.077, is outside
  EXPECT_NEAR(e.root[0], (4.8 - std::sqrt(4.8 * 4.8 - 12 * 1.69)) / 6.0, 1e-14);
  ASSERT_TRUE(e.has_vertex);
  EXPECT_NEAR(e.vertex, 0.8, 1e-14);
  // A quadratic (q'' constant) has no velocity vertex; a monotone cubic has no position extremum.
  EXPECT_FALSE(cubic_extrema(1.0, -1.0, -1.0).has_vertex);
  EXPECT_EQ(cubic_extrema(1.0, 0.5, 0.7).roots, 0);
}

TEST(ExactLimits, SplineMaxAbsIsExactAndSeesOvershootBetweenWaypoints) {
  // Flat - steep - flat waypoints: every chord is within 1 rad/s (eq 17 holds) but the C1 cubic
  // through them overshoots between waypoints, in velocity and in position.
  Eigen::MatrixXd W(1, 7);
  W << 0.0, 0.0, 0.0, 0.1, 0.1, 0.1, 0.1;
  const double T = 0.6;  // dt = 0.1 s, steepest chord 1 rad/s
  const SplineTrajectory s(W, Eigen::VectorXd::Constant(1, -0.5), Eigen::VectorXd::Zero(1), T);
  double pos, vel;
  s.max_abs(0, pos, vel);
  double dense_pos = 0.0, dense_vel = 0.0;
  const int K = 600000;
  for (int k = 0; k <= K; ++k) {
    double q, dq, ddq;
    s.evaluate(0, T * k / K, q, dq, ddq);
    dense_pos = std::max(dense_pos, std::abs(q));
    dense_vel = std::max(dense_vel, std::abs(dq));
  }
  EXPECT_GE(pos, dense_pos - 1e-15);
  EXPECT_LE(pos, dense_pos + 1e-10);
  EXPECT_GE(vel, dense_vel - 1e-15);
  EXPECT_LE(vel, dense_vel + 1e-8);
  EXPECT_GT(vel, 1.2);  // 25 % above the steepest chord (Catmull–Rom tangents 0.5, chord 1)
  EXPECT_GT(pos, 0.1);  // overshoots the last waypoint
}

// t1 swept over the squirming period (40 values) with the nine Table 1
// configurations; no joint-limit violation above 1e-9, neither densely sampled (2000 points per
// transition) nor at the analytic extrema, and the reported max_violation agrees with both.
// Bezier also runs the opposite direction (wheel-walking -> squirming). Linear and Spline run with
// a 0.1 s budget to keep the test short: the exact rows and the final check do not depend on it
// (a point SLSQP leaves infeasible falls back to Naive, which is checked the same way).
TEST(ExactLimits, NoViolationAnywhereOverTheSquirmingPeriod) {
  const AsterixParameters p;
  const Gait sq = squirming(p), ww = wheel_walking(p);
  const int N = 40;
  for (Strategy s : {Strategy::Bezier, Strategy::Linear, Strategy::Spline}) {
    for (WeightSet ws : {WeightSet::Duration, WeightSet::Deviation, WeightSet::Balanced}) {
      TransitionOptions o;
      if (s != Strategy::Bezier) o.solver.max_time = 0.1;
      const CostWeights w = CostWeights::table1(s, ws);
      for (int dir = 0; dir < (s == Strategy::Bezier ? 2 : 1); ++dir) {
        const Gait& from = dir == 0 ? sq : ww;
        const Gait& to = dir == 0 ? ww : sq;
        double worst = -HUGE_VAL;
        for (int k = 0; k < N; ++k) {
          const TransitionProblem pb(p, from, to, from.period() * k / N);
          const TransitionResult r = plan_transition(pb, s, w, o);
          if (s == Strategy::Bezier) {
            ASSERT_FALSE(r.fell_back) << r.fallback_reason;
          }
          const double dense = dense_violation(pb, r), exact = analytic_violation(pb, r);
          const std::string where = to_string(s) + "/" + to_string(ws) + " dir " +
                                    std::to_string(dir) + " t1 " + std::to_string(pb.t1);
          EXPECT_LE(dense, 1e-9) << where;
          EXPECT_LE(exact, 1e-9) << where;
          EXPECT_NEAR(r.max_violation, exact, 1e-12) << where;
          EXPECT_GE(r.max_violation, dense - 1e-12) << where;   // samples never see more
          EXPECT_LE(r.max_violation, dense + 1e-5) << where;    // and miss little between them
          worst = std::max(worst, exact);
        }
        // The duration weights drive the steering speed onto its limit: the bound is active.
        if (s == Strategy::Bezier && ws == WeightSet::Duration) EXPECT_GT(worst, -1e-6);
      }
    }
  }
}
