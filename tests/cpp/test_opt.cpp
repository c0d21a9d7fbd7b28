// Tests of cpp/opt (seed 000): NLopt wrapper, Asterix kinematics (eqs 20–23), gaits (eq 1),
// the four transition strategies (eqs 2–19) and the metrics (eqs 24–28).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "ernest/opt/asterix_model.hpp"
#include "ernest/opt/gait.hpp"
#include "ernest/opt/metrics.hpp"
#include "ernest/opt/nlopt_solver.hpp"
#include "ernest/opt/transition.hpp"

using namespace ernest::opt;

namespace {

// NLopt's tutorial problem: min sqrt(x2) s.t. x2 >= (a x1 + b)^3 for (a, b) = (2, 0), (-1, 1).
OptimizationProblem tutorial_problem() {
  OptimizationProblem p;
  p.dimension = 2;
  p.lower = {-HUGE_VAL, 0.0};
  p.upper = {HUGE_VAL, HUGE_VAL};
  p.objective = [](const double* x, double* g) {
    if (g) {
      g[0] = 0.0;
      g[1] = 0.5 / std::sqrt(x[1]);
    }
    return std::sqrt(x[1]);
  };
  p.inequality.push_back({2, [](const double* x, double* c, double* J) {
                            const double ab[2][2] = {{2.0, 0.0}, {-1.0, 1.0}};
                            for (int i = 0; i < 2; ++i) {
                              const double a = ab[i][0], b = ab[i][1], u = a * x[0] + b;
                              c[i] = u * u * u - x[1];
                              if (J) {
                                J[2 * i + 0] = 3.0 * a * u * u;
                                J[2 * i + 1] = -1.0;
                              }
                            }
                          }});
  return p;
}

struct CustomError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

SteeringFunction constant_steering(double theta) {
  return [theta](double, double& th, double& rate) {
    th = theta;
    rate = 0.0;
  };
}

// Asterix problem squirming -> wheel-walking at t1.
TransitionProblem asterix_problem(double t1) {
  const AsterixParameters p;
  return TransitionProblem(p, squirming(p), wheel_walking(p), t1);
}

// Figs 2–4: one joint, g1 = sin(t), g2 = 0.5 sin(2t) + 0.2 (a "steering-only rover").
TransitionProblem sinusoid_problem(double t1) {
  AsterixParameters p;
  p.steering_limit = 1.3;
  Eigen::VectorXd one(1), zero(1), half(1), off(1);
  one << 1.0;
  zero << 0.0;
  half << 0.5;
  off << 0.2;
  Gait g1("sin(t)", 2.0 * M_PI, zero, one, zero);
  Gait g2("0.5 sin(2t) + 0.2", M_PI, off, half, zero);
  Eigen::VectorXd pos(1), vel(1), acc(1);
  pos << 1.3;
  vel << 1.5;
  acc << 2.0;
  return TransitionProblem(p, g1, g2, t1, pos, vel, acc);
}

void expect_c1_boundaries(const TransitionProblem& pb, const TransitionResult& r, double tol) {
  for (int j = 0; j < pb.joints(); ++j) {
    double q, dq, ddq, g, dg, ddg;
    r.evaluate(j, 0.0, q, dq, ddq);
    pb.from.evaluate(j, pb.t1, g, dg, ddg);
    EXPECT_NEAR(q, g, tol) << "eq 2, joint " << j;
    EXPECT_NEAR(dq, dg, tol) << "eq 4, joint " << j;
    r.evaluate(j, r.duration, q, dq, ddq);
    // eqs 3 and 5 with the returned phase shift: g2(t1 + T - phi)
    pb.to.evaluate(j, pb.t1 + r.duration - r.phase_shift, g, dg, ddg);
    EXPECT_NEAR(q, g, tol) << "eq 3, joint " << j;
    EXPECT_NEAR(dq, dg, tol) << "eq 5, joint " << j;
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// NLopt wrapper

TEST(NloptWrapper, SolvesTheNloptTutorialProblem) {
  SolverOptions o;
  o.xtol_rel = 1e-10;
  o.ftol_rel = 0.0;
  o.ftol_abs = 0.0;
  o.max_time = 5.0;
  const SolverResult r = minimize_slsqp(tutorial_problem(), {1.234, 5.678}, o);
  EXPECT_TRUE(r.converged()) << r.status_name;
  EXPECT_NEAR(r.x[0], 1.0 / 3.0, 1e-6);
  EXPECT_NEAR(r.x[1], 8.0 / 27.0, 1e-6);
  EXPECT_NEAR(r.value, std::sqrt(8.0 / 27.0), 1e-7);
  EXPECT_NEAR(r.value, 0.544331, 1e-6);
  EXPECT_GT(r.evaluations, 0);
}

TEST(NloptWrapper, RethrowsObjectiveExceptionWithItsType) {
  OptimizationProblem p = tutorial_problem();
  int calls = 0;
  p.objective = [&calls](const double* x, double* g) -> double {
    if (++calls == 3) throw CustomError("boom in objective");
    if (g) {
      g[0] = 0.0;
      g[1] = 0.5 / std::sqrt(x[1]);
    }
    return std::sqrt(x[1]);
  };
  EXPECT_THROW(minimize_slsqp(p, {1.234, 5.678}), CustomError);
  EXPECT_EQ(calls, 3);  // the run stopped right after the exception
}

TEST(NloptWrapper, RethrowsConstraintExceptionWithItsType) {
  OptimizationProblem p = tutorial_problem();
  p.inequality[0].function = [](const double*, double*, double*) {
    throw std::out_of_range("boom in constraint");
  };
  EXPECT_THROW(minimize_slsqp(p, {1.234, 5.678}), std::out_of_range);
}

TEST(NloptWrapper, RejectsIllFormedProblems) {
  OptimizationProblem p = tutorial_problem();
  EXPECT_THROW(minimize_slsqp(p, {1.0}), std::invalid_argument);
  SolverOptions o;
  o.max_time = -1.0;
  EXPECT_THROW(minimize_slsqp(p, {1.0, 1.0}, o), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Kinematics (eqs 20–23)

TEST(AsterixKinematics, ParametersAreValidatedByName) {
  AsterixParameters p;
  p.mass = -1.0;
  try {
    p.validate();
    FAIL() << "negative mass accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("mass"), std::string::npos);
  }
}

TEST(AsterixKinematics, ZeroSteeringDrivesStraightAtROmega) {
  const AsterixParameters p;
  const AsterixKinematics kin(p);
  for (double w : kin.wheel_speeds(0.0, 0.0)) EXPECT_NEAR(p.wheel_radius * w, p.forward_speed, 1e-15);
  const Pose2 start{0.3, -0.2, 0.7};
  const double T = 10.0;
  const Pose2 end = kin.integrate(constant_steering(0.0), 0.0, T, start);
  EXPECT_NEAR(end.heading, start.heading, 1e-14);
  EXPECT_NEAR(end.x, start.x + p.forward_speed * T * std::cos(0.7), 1e-9);
  EXPECT_NEAR(end.y, start.y + p.forward_speed * T * std::sin(0.7), 1e-9);
}

TEST(AsterixKinematics, ConstantSteeringTracesTheDerivedCircle) {
  const AsterixParameters p;
  const AsterixKinematics kin(p);
  for (double theta : {0.4, -0.25}) {
    const double h = 0.5 * theta;
    // Geometry (independent of the integrator): both axle centres lie on a circle about the
    // instantaneous centre, radius l_x / tan(|theta|/2) (articulated frame, joint mid-wheelbase).
    const WheelStates w = kin.wheel_states(Pose2{}, theta);
    const double fx = 0.5 * (w[0][0] + w[1][0]), fy = 0.5 * (w[0][1] + w[1][1]);
    const double rx = 0.5 * (w[2][0] + w[3][0]), ry = 0.5 * (w[2][1] + w[3][1]);
    const double radius = kin.turning_radius(theta);
    EXPECT_NEAR(radius, p.l_x * std::cos(h) / std::tan(std::abs(h)), 1e-12);
    // Centre on the side the rover turns to: theta > 0 turns clockwise (eq 22 sign).
    const double cy = theta > 0 ? -radius : radius;
    const double axle_radius = p.l_x / std::tan(std::abs(h));
    EXPECT_NEAR(std::hypot(fx, fy - cy), axle_radius, 1e-12);
    EXPECT_NEAR(std::hypot(rx, ry - cy), axle_radius, 1e-12);
    // Integrated reference point stays on the circle; heading follows eq 22 exactly.
    for (double T : {1.0, 5.0, 20.0}) {
      const Pose2 e = kin.integrate(constant_steering(theta), 0.0, T, Pose2{});
      EXPECT_NEAR(std::hypot(e.x, e.y - cy), radius, 1e-8) << "T=" << T;
      EXPECT_NEAR(e.heading, p.forward_speed / p.l_x * std::tan(-h) * T, 1e-10);
    }
  }
}

TEST(AsterixKinematics, WheelEquationsAgreeWithPoseAndStayRigid) {
  // Eqs 20–22 integrated per wheel with the synchronised wheel speeds must (a) average to the
  // reference pose (eq 23) and (b) keep the wheels where the rigid geometry puts them: no skid.
  const AsterixParameters p;
  const AsterixKinematics kin(p);
  const Gait g = wheel_walking(p);
  auto steering = [&g](double t, double& th, double& rate) {
    double acc;
    g.evaluate(kSteering, t, th, rate, acc);
  };
  const Pose2 start{1.0, 2.0, 0.3};
  const double t0 = 0.7, t1 = 13.0;
  const Pose2 pose = kin.integrate(steering, t0, t1, start);
  const WheelStates wheels = kin.integrate_wheels(steering, t0, t1, start);
  const Pose2 mean = AsterixKinematics::pose_from_wheels(wheels);
  EXPECT_NEAR(mean.x, pose.x, 1e-7);
  EXPECT_NEAR(mean.y, pose.y, 1e-7);
  EXPECT_NEAR(mean.heading, pose.heading, 1e-9);
  double th, rate, acc;
  g.evaluate(kSteering, t1, th, rate, acc);
  const WheelStates rigid = kin.wheel_states(pose, th);
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(wheels[i][k], rigid[i][k], 1e-7) << i << "," << k;
}

TEST(AsterixKinematics, NoProgressIsReported) {
  const AsterixKinematics kin(AsterixParameters{});
  IntegrationOptions o;
  o.max_steps = 2;
  const Gait g = squirming();
  auto steering = [&g](double t, double& th, double& rate) {
    double acc;
    g.evaluate(kSteering, t, th, rate, acc);
  };
  EXPECT_THROW(kin.integrate(steering, 0.0, 100.0, Pose2{}, o), KinematicsError);
}

// ---------------------------------------------------------------------------------------------
// Gaits (eq 1)

TEST(Gaits, SquirmingAndWheelWalkingMatchThePaper) {
  const AsterixParameters p;
  const Gait s = squirming(p), w = wheel_walking(p);
  double max_steer = 0.0, max_roll_s = 0.0, max_roll_w = 0.0;
  for (int k = 0; k < 1000; ++k) {
    const double t = s.period() * k / 1000.0;
    max_steer = std::max(max_steer, std::abs(s.position(t)[kSteering]));
    max_roll_s = std::max(max_roll_s, std::abs(s.position(t)[kRoll]));
    max_roll_w = std::max(max_roll_w, std::abs(w.position(t * w.period() / s.period())[kRoll]));
    // velocity is the derivative of the position (central difference)
    const double h = 1e-5;
    const Eigen::VectorXd fd = (w.position(t + h) - w.position(t - h)) / (2 * h);
    EXPECT_NEAR((fd - w.velocity(t)).norm(), 0.0, 1e-8);
  }
  EXPECT_NEAR(max_steer, 0.92 * p.steering_limit, 1e-5);  // squirming: between its limits
  EXPECT_EQ(max_roll_s, 0.0);                             // squirming: roll fixed
  EXPECT_GT(max_roll_w, 0.25);                            // wheel-walking: roll oscillates
  // Periodic and symmetric squirming: no net heading change over a period.
  const AsterixKinematics kin(p);
  EXPECT_NEAR(gait_pose(kin, s, 0.0, s.period()).heading, 0.0, 1e-9);
}

// ---------------------------------------------------------------------------------------------
// Strategies

TEST(Transitions, Table1Weights) {
  const CostWeights b = CostWeights::table1(Strategy::Bezier, WeightSet::Duration);
  EXPECT_EQ(b.duration, 30.0);
  EXPECT_EQ(b.acceleration, 1.0);
  EXPECT_EQ(b.deviation, 1.0);
  const CostWeights l = CostWeights::table1(Strategy::Linear, WeightSet::Deviation);
  EXPECT_EQ(l.duration, 4.0);
  EXPECT_EQ(l.acceleration, 5.0);
  EXPECT_EQ(l.deviation, 20.0);
  const CostWeights s = CostWeights::table1(Strategy::Spline, WeightSet::Balanced);
  EXPECT_EQ(s.duration, 4.0);
  EXPECT_EQ(s.acceleration, 5.0);
  EXPECT_EQ(s.deviation, 1.0);
}

TEST(Transitions, AnalyticGradientsMatchFiniteDifferences) {
  const TransitionProblem pb = asterix_problem(1.3);
  TransitionOptions o;
  o.waypoints = 12;  // same code path as 100, cheaper to difference
  for (Strategy s : {Strategy::Bezier, Strategy::Linear, Strategy::Spline}) {
    const int n = transition_dimension(pb, s, o);
    std::vector<double> x(n);
    x[0] = 1.7;
    x[1] = 2.9;
    for (int i = 2; i < n; ++i) x[i] = 0.2 * std::sin(0.7 * i);
    std::vector<double> g;
    const CostWeights w = CostWeights::table1(s, WeightSet::Balanced);
    transition_cost(pb, s, w, o, x, &g);
    for (int i = 0; i < n; ++i) {
      std::vector<double> xp = x, xm = x;
      const double h = 1e-6 * std::max(1.0, std::abs(x[i]));
      xp[i] += h;
      xm[i] -= h;
      const double fd =
          (transition_cost(pb, s, w, o, xp) - transition_cost(pb, s, w, o, xm)) / (2 * h);
      EXPECT_NEAR(g[i], fd, 1e-5 * (1.0 + std::abs(fd))) << to_string(s) << " x[" << i << "]";
    }
    std::vector<double> c, J;
    transition_constraints(pb, s, o, x, c, &J);
    const int m = static_cast<int>(c.size());
    for (int i = 0; i < n; ++i) {
      std::vector<double> xp = x, xm = x, cp, cm;
      xp[i] += 1e-6;
      xm[i] -= 1e-6;
      transition_constraints(pb, s, o, xp, cp);
      transition_constraints(pb, s, o, xm, cm);
      for (int r = 0; r < m; ++r)
        ASSERT_NEAR(J[r * n + i], (cp[r] - cm[r]) / 2e-6, 1e-6) << to_string(s) << " row " << r;
    }
  }
}

TEST(Transitions, BezierIsContinuousInPositionAndVelocity) {
  for (double t1 : {0.0, 1.6, 3.2, 4.8, 6.4}) {
    const TransitionProblem pb = asterix_problem(t1);
    for (WeightSet ws : {WeightSet::Duration, WeightSet::Deviation, WeightSet::Balanced}) {
      const TransitionResult r =
          plan_transition(pb, Strategy::Bezier, CostWeights::table1(Strategy::Bezier, ws));
      ASSERT_FALSE(r.fell_back) << r.fallback_reason;
      EXPECT_EQ(r.strategy, Strategy::Bezier);
      expect_c1_boundaries(pb, r, 1e-6);
      // Eqs 9–13 with the corrected basis and T/3: an independent evaluation of the cubic.
      const double T = r.duration, sigma = pb.t1 + T - r.phase_shift;
      for (int j = 0; j < pb.joints(); ++j) {
        const double p0 = pb.from.position(t1)[j], p3 = pb.to.position(sigma)[j];
        const double p1 = p0 + T / 3.0 * pb.from.velocity(t1)[j];
        const double p2 = p3 - T / 3.0 * pb.to.velocity(sigma)[j];
        for (double s : {0.1, 0.37, 0.5, 0.81}) {
          const double u = 1.0 - s;
          const double ref = u * u * u * p0 + 3 * u * u * s * p1 + 3 * u * s * s * p2 + s * s * s * p3;
          double q, dq, ddq;
          r.evaluate(j, s * T, q, dq, ddq);
          EXPECT_NEAR(q, ref, 1e-12);
        }
        // Joint limits hold along the curve.
        for (int k = 0; k <= 200; ++k) {
          double q, dq, ddq;
          r.evaluate(j, T * k / 200.0, q, dq, ddq);
          EXPECT_LE(std::abs(q), pb.position_limit[j] * (1 + 1e-6));
        }
      }
    }
  }
}

TEST(Transitions, LinearAndSplineMeetEndpointsAndWaypointBounds) {
  const TransitionProblem pb = asterix_problem(2.4);
  for (Strategy s : {Strategy::Linear, Strategy::Spline}) {
    const TransitionResult r =
        plan_transition(pb, s, CostWeights::table1(s, WeightSet::Balanced));
    ASSERT_FALSE(r.fell_back) << r.fallback_reason;
    const Eigen::MatrixXd& W = r.spline.waypoints();
    ASSERT_EQ(W.cols(), 100);
    const double sigma = pb.t1 + r.duration - r.phase_shift;
    const double dt = r.duration / (W.cols() - 1);
    for (int j = 0; j < pb.joints(); ++j) {
      EXPECT_NEAR(W(j, 0), pb.from.position(pb.t1)[j], 1e-12);   // eq 14
      EXPECT_NEAR(W(j, W.cols() - 1), pb.to.position(sigma)[j], 1e-12);  // eq 15 (with phi)
      for (int i = 0; i < W.cols(); ++i) {
        EXPECT_LE(std::abs(W(j, i)), pb.position_limit[j] + 1e-9);  // eq 16
        if (i > 0) {
          EXPECT_LE(std::abs(W(j, i) - W(j, i - 1)) / dt, pb.velocity_limit[j] * (1 + 1e-5));  // eq 17
        }
      }
    }
    expect_c1_boundaries(pb, r, 1e-6);  // the Bezier joins give C1 with both gaits
    EXPECT_LE(r.max_violation, 1e-6);
  }
}

TEST(Transitions, NaiveRespectsVelocityAndAccelerationLimits) {
  const TransitionProblem pb = asterix_problem(1.0);
  const TransitionResult r = plan_transition(pb, Strategy::Naive);
  EXPECT_EQ(r.strategy, Strategy::Naive);
  EXPECT_NEAR(r.phase_shift, pb.t1 + r.duration, 1e-12);  // continue with g2 from phase 0
  double slowest = 0.0;
  for (int j = 0; j < pb.joints(); ++j) {
    const double d = std::abs(pb.to.position(0.0)[j] - pb.from.position(pb.t1)[j]);
    const double v = pb.velocity_limit[j], a = pb.acceleration_limit[j];
    slowest = std::max(slowest, d <= v * v / a ? 2 * std::sqrt(d / a) : d / v + v / a);
    double q, dq, ddq;
    r.evaluate(j, 0.0, q, dq, ddq);
    EXPECT_NEAR(q, pb.from.position(pb.t1)[j], 1e-12);
    EXPECT_EQ(dq, 0.0);
    r.evaluate(j, r.duration, q, dq, ddq);
    EXPECT_NEAR(q, pb.to.position(0.0)[j], 1e-12);
    EXPECT_NEAR(dq, 0.0, 1e-12);
    double prev_q = pb.from.position(pb.t1)[j], prev_v = 0.0;
    const int K = 2000;
    const double h = r.duration / K;
    for (int k = 1; k <= K; ++k) {
      r.evaluate(j, k * h, q, dq, ddq);
      EXPECT_LE(std::abs(dq), v * (1 + 1e-12));
      EXPECT_LE(std::abs(ddq), a * (1 + 1e-12));
      EXPECT_LE(std::abs(q - prev_q) / h, v * (1 + 1e-9));      // finite-difference velocity
      EXPECT_LE(std::abs(dq - prev_v) / h, a * (1 + 1e-9));     // finite-difference acceleration
      prev_q = q;
      prev_v = dq;
    }
  }
  EXPECT_NEAR(r.duration, slowest, 1e-12);  // minimum time of the slowest joint
}

TEST(Transitions, BudgetIsHonoured) {
  const TransitionProblem pb = asterix_problem(3.2);
  TransitionOptions o;
  o.solver.max_time = 0.5;
  for (Strategy s : {Strategy::Spline, Strategy::Linear}) {
    const CostWeights w = CostWeights::table1(s, WeightSet::Deviation);
    // Cost of one evaluation: objective with gradient plus constraints with Jacobian.
    const int n = transition_dimension(pb, s, o);
    std::vector<double> x(n, 0.0), g, c, J;
    x[0] = 1.5;
    const auto t0 = std::chrono::steady_clock::now();
    transition_cost(pb, s, w, o, x, &g);
    transition_constraints(pb, s, o, x, c, &J);
    const double one_eval =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto t1 = std::chrono::steady_clock::now();
    const TransitionResult r = plan_transition(pb, s, w, o);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    // NLopt can stop only between evaluations, so "one evaluation" here is one SLSQP iteration
    // (its dense QP plus our cost and constraints), measured in this run.
    const double one_iteration = r.solver.seconds / std::max(1, r.solver.evaluations) + one_eval;
    EXPECT_LE(wall, o.solver.max_time + one_iteration)
        << to_string(s) << " one iteration " << one_iteration;
    EXPECT_FALSE(r.fell_back) << r.fallback_reason;
    EXPECT_LE(r.max_violation, o.feasibility_tol);
  }
}

TEST(Transitions, TwoSinusoidsGiveSmoothTransitionsForEveryStrategy) {
  // Figs 2–4: t1 = 2, 3 pi / 2, pi / 4.
  for (double t1 : {2.0, 1.5 * M_PI, 0.25 * M_PI}) {
    const TransitionProblem pb = sinusoid_problem(t1);
    for (Strategy s : {Strategy::Naive, Strategy::Bezier, Strategy::Linear, Strategy::Spline}) {
      TransitionOptions o;
      o.solver.max_time = 0.3;
      const TransitionResult r =
          plan_transition(pb, s, CostWeights::table1(s, WeightSet::Balanced), o);
      ASSERT_FALSE(r.fell_back) << to_string(s) << ": " << r.fallback_reason;
      // Position is continuous into g2(t - phi) and every sample is finite and within limits.
      double prev_q = 0.0;
      const int K = 4000;
      const double span = r.duration + 2.0, h = span / K;
      double max_jump = 0.0, max_acc = 0.0;
      for (int k = 0; k <= K; ++k) {
        const double t = pb.t1 - 1.0 + k * h;
        double q, dq, ddq;
        r.executed(pb, 0, t, q, dq, ddq);
        ASSERT_TRUE(std::isfinite(q) && std::isfinite(dq) && std::isfinite(ddq));
        EXPECT_LE(std::abs(q), pb.position_limit[0] * (1 + 1e-6));
        if (k > 0) max_jump = std::max(max_jump, std::abs(q - prev_q));
        if (t >= pb.t1 && t <= pb.t1 + r.duration) max_acc = std::max(max_acc, std::abs(ddq));
        prev_q = q;
      }
      EXPECT_LE(max_jump, 1.6 * h) << to_string(s) << " t1=" << t1;  // no jump: |dq| <= 1.5
      EXPECT_LE(max_acc, 20.0) << to_string(s);
      if (s != Strategy::Naive) {
        expect_c1_boundaries(pb, r, 1e-6);
      } else {
        // Naive: trapezoid within its limits; position continuous at both ends.
        EXPECT_LE(max_acc, pb.acceleration_limit[0] * (1 + 1e-12));
      }
    }
  }
}

TEST(Transitions, FailureFallsBackToNaiveWithReason) {
  const TransitionProblem pb = asterix_problem(1.0);
  TransitionOptions o;
  o.integration.max_steps = 1;  // odeint cannot make progress: every cost evaluation throws
  const TransitionResult r = plan_transition(pb, Strategy::Bezier, {}, o);
  EXPECT_TRUE(r.fell_back);
  EXPECT_EQ(r.requested, Strategy::Bezier);
  EXPECT_EQ(r.strategy, Strategy::Naive);
  EXPECT_NE(r.fallback_reason.find("bezier"), std::string::npos) << r.fallback_reason;
  o.fallback = false;
  EXPECT_THROW(plan_transition(pb, Strategy::Bezier, {}, o), std::runtime_error);
}

// ---------------------------------------------------------------------------------------------
// Metrics (eqs 24–28)

TEST(Metrics, ResidualsEnergyAndCostOfTransport) {
  const TransitionProblem pb = asterix_problem(2.0);
  const TransitionResult bez =
      plan_transition(pb, Strategy::Bezier, CostWeights::table1(Strategy::Bezier, WeightSet::Balanced));
  const TransitionMetrics m = evaluate_metrics(pb, bez);
  EXPECT_LE(m.start_position_residual, 1e-9);
  EXPECT_LE(m.start_velocity_residual, 1e-9);
  EXPECT_LE(m.end_position_residual, 1e-9);
  EXPECT_LE(m.end_velocity_residual, 1e-9);
  const AsterixParameters& p = pb.rover;
  EXPECT_NEAR(m.energy, m.energy_wheels + m.energy_articulation, 1e-12);  // eq 25
  EXPECT_NEAR(m.cost_of_transport, m.energy / (p.mass * p.gravity * m.distance), 1e-12);  // eq 24
  // Wheels alone: sum_i C_rr m g / 4 |R w_i| >= C_rr m g x (path length) >= C_rr m g d.
  EXPECT_GE(m.energy_wheels, p.rolling_resistance * p.mass * p.gravity * m.distance * (1 - 1e-6));
  EXPECT_NEAR(m.heading_change, m.end_pose.heading - m.start_pose.heading, 1e-15);

  const TransitionResult naive = plan_transition(pb, Strategy::Naive);
  const TransitionMetrics n = evaluate_metrics(pb, naive);
  // Naive starts and ends at rest: its velocity residuals are the gaits' speeds there.
  EXPECT_NEAR(n.start_velocity_residual, pb.from.velocity(pb.t1).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(n.end_velocity_residual, pb.to.velocity(0.0).cwiseAbs().maxCoeff(), 1e-12);
  // ...and the telemetry sees the velocity step as a large acceleration (Fig. 10).
  const double dt = 1.0 / 50.0;
  EXPECT_GE(n.max_acceleration[kSteering],
            0.5 * std::abs(pb.from.velocity(pb.t1)[kSteering]) / dt);
}
