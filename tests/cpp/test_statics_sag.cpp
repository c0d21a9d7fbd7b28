// Tests of the compliance (sag) model, seed 003 §5.1.1 eqs 1–12: closed forms (uniform sag
// mg/(N k_zz), small-angle pitch of a rectangle), the rigid limit (the pseudo-inverse
// distribution), gradual unloading of a lifted foot, every combination of feet in the air,
// rotation equivariance and input checks; the spring-constant calibration (§5.1.3–5.1.4).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "ernest/statics/calibration.hpp"
#include "ernest/statics/force_distribution.hpp"
#include "ernest/statics/sag.hpp"
#include "ernest/statics/stability.hpp"
#include "test_util.hpp"

using namespace ernest::statics;
using ernest::testing::invalid_argument_message;

namespace {
constexpr double kG = 9.81;

// A hexagonal stance (ATHLETE-like scale: 850 kg, feet on a 2.5 m circle, CG 1.75 m up).
SagProblem hexapod(double k_xy = 2e5, double k_z = 1e5) {
  SagProblem p;
  p.feet.resize(3, 6);
  p.body_points.resize(3, 6);
  for (int i = 0; i < 6; ++i) {
    const double t = M_PI / 3 * i;
    p.feet.col(i) << 2.5 * std::cos(t), 2.5 * std::sin(t), 0.0;
    p.body_points.col(i) << 1.2 * std::cos(t), 1.2 * std::sin(t), 1.9;  // leg attachments
  }
  p.stiffness.resize(3, 6);
  p.stiffness.row(0).setConstant(k_xy);
  p.stiffness.row(1).setConstant(k_xy);
  p.stiffness.row(2).setConstant(k_z);
  p.cg << 0.0, 0.0, 1.75;
  p.mass = 850.0;
  p.chassis_position << 0.0, 0.0, 1.9;
  return p;
}
}  // namespace

TEST(Sag, SymmetricStanceSagsUniformly) {
  for (int n : {3, 4, 6, 8}) {
    SagProblem p = hexapod();
    p.feet.resize(3, n);
    p.stiffness.resize(3, n);
    p.stiffness.setConstant(1.5e5);
    for (int i = 0; i < n; ++i) p.feet.col(i) << 2 * std::cos(2 * M_PI * i / n), 2 * std::sin(2 * M_PI * i / n), 0;
    const SagResult r = solve_sag(p);
    ASSERT_EQ(r.status, SagStatus::Converged) << n;
    const double sag = p.mass * kG / (n * 1.5e5);  // mg / (N k_zz)
    EXPECT_EQ(r.loaded, n);
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(r.deflections(2, i), -sag, 1e-12) << n;
      EXPECT_NEAR(r.forces(2, i), p.mass * kG / n, 1e-7);
      EXPECT_NEAR(r.forces.col(i).head<2>().norm(), 0.0, 1e-7);
    }
    EXPECT_NEAR(r.cg.z(), 1.75 - sag, 1e-12);
    EXPECT_NEAR(r.chassis_position.z(), 1.9 - sag, 1e-12);
    EXPECT_LT((r.rotation - Eigen::Matrix3d::Identity()).norm(), 1e-10);
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(r.body_points(2, i), 1.9 - sag, 1e-12);
    EXPECT_LT(r.rigidity_residual, 1e-12);
  }
}

TEST(Sag, RectanglePitchMatchesSmallAngleClosedForm) {
  // Four feet at (±a, ±b), CG offset x0 forward: front feet carry W/4 + W x0/(4a), back ones
  // W/4 - W x0/(4a); vertical springs k give the pitch (f_front - f_back)/(2 a k).
  SagProblem p;
  const double a = 1.5, b = 1.0, x0 = 0.3, k = 1e7;
  p.feet.resize(3, 4);
  p.feet << a, -a, -a, a, b, b, -b, -b, 0, 0, 0, 0;
  p.stiffness = Eigen::Matrix3Xd::Constant(3, 4, k);
  p.cg << x0, 0, 1.0;
  p.mass = 500.0;
  const SagResult r = solve_sag(p);
  ASSERT_EQ(r.status, SagStatus::Converged);
  const double W = p.mass * kG;
  const double f_front = W / 4 + W * x0 / (4 * a), f_back = W / 4 - W * x0 / (4 * a);
  EXPECT_NEAR(r.forces(2, 0), f_front, 1e-4 * W);
  EXPECT_NEAR(r.forces(2, 1), f_back, 1e-4 * W);
  const double pitch = std::asin(r.rotation(2, 0));  // nose down: rotation about +y, R(2,0) < 0
  EXPECT_NEAR(-pitch, (f_front - f_back) / (2 * a * k), 1e-3 * (f_front - f_back) / (2 * a * k));
}

TEST(Sag, StiffSpringsApproachThePseudoInverse) {
  // Isotropic springs: a small rigid displacement (t, w) gives f_i = -k (t + w x p_i), the
  // zero-interaction form, so the sag forces tend to A^+ w as k grows (the geometry change,
  // O(1/k), is the only difference).
  SagProblem p = hexapod();
  p.cg << 0.4, -0.3, 1.75;
  p.feet(2, 2) = 0.2;   // uneven ground
  p.feet(0, 4) -= 0.3;  // irregular stance
  const Eigen::Matrix3Xd ref = zero_interaction_forces(p.feet, p.cg, p.mass, p.gravity);
  double previous = 1e300;
  for (double k : {1e5, 1e6, 1e7, 1e8}) {
    p.stiffness.setConstant(k);
    const SagResult r = solve_sag(p);
    ASSERT_EQ(r.status, SagStatus::Converged) << k;
    const double err = (r.forces - ref).norm() / ref.norm();
    EXPECT_LT(err, previous / 5) << k;  // at least 5x closer per decade
    previous = err;
  }
  EXPECT_LT(previous, 1e-5);
}

TEST(Sag, LiftedFootUnloadsGraduallyAndStaysUnloaded) {
  SagProblem p = hexapod();
  p.cg << 0.1, 0.05, 1.75;
  p.lift = Eigen::VectorXd::Zero(6);
  const double full = solve_sag(p).forces(2, 0);
  // Where foot 0 stops touching: the five-foot stance (foot 0 in the air) lowers its fork by
  // -d_z; the foot carries load exactly while Δh < -d_z.
  SagProblem five = p;
  five.lift(0) = std::numeric_limits<double>::infinity();
  const double release = -solve_sag(five).deflections(2, 0);
  const double step = release / 25;
  double last = full;
  for (int s = 0; s <= 50; ++s) {
    const double dh = step * s;
    SagProblem q = p;
    q.feet(2, 0) += dh;  // the fork is raised by Δh (eq 9) ...
    q.lift(0) = dh;      // ... above the point where its tyre touches
    const SagResult r = solve_sag(q);
    ASSERT_EQ(r.status, SagStatus::Converged) << dh;
    const double fz = r.forces(2, 0);
    EXPECT_LE(fz, last + 1e-9);        // monotone
    EXPECT_LT(last - fz, 0.1 * full);  // continuous: no jump larger than 10 % per step
    if (dh < release - 1e-9) {
      EXPECT_GT(fz, 0.0) << dh;
      EXPECT_EQ(r.loaded, 6);
    } else {
      EXPECT_EQ(fz, 0.0) << dh;  // reaches zero and stays zero
      EXPECT_EQ(r.loaded, 5);
    }
    last = fz;
  }
}

TEST(Sag, EveryCombinationOfFeetInTheAir) {
  // Hexagon, CG near the centre. With a rigid-body margin (SSM of the feet left down) above
  // 0.3 m the robot must stand on exactly those feet; with a negative one, or fewer than three
  // feet, it must be Unstable. In between, sag can tilt the CG (1.75 m up) over the edge
  // (4 cm of sag on one side tilts it ~3 cm), so either answer may be right, but it must be one
  // of the two and, if standing, consistent (no pulling foot, lifted feet unloaded).
  const SagProblem base = hexapod();
  const ProjectionFrame frame = ProjectionFrame::from_gravity(base.gravity);
  int stable = 0, unstable = 0;
  for (int mask = 0; mask < 64; ++mask) {
    SagProblem p = base;
    p.cg << 0.05, 0.02, 1.75;
    p.lift = Eigen::VectorXd::Zero(6);
    Eigen::Matrix3Xd down(3, 6);
    int m = 0;
    for (int i = 0; i < 6; ++i) {
      if (mask & (1 << i)) {
        p.lift(i) = std::numeric_limits<double>::infinity();
      } else {
        down.col(m++) = p.feet.col(i);
      }
    }
    const SagResult r = solve_sag(p);
    const double ssm =
        m >= 3 ? static_stability_margin(support_polygon(down.leftCols(m), frame), p.cg, frame)
               : -1.0;
    EXPECT_TRUE(r.forces.allFinite() && r.deflections.allFinite() && r.cg.allFinite());
    if (ssm > 0.3) {
      EXPECT_EQ(r.status, SagStatus::Converged) << mask;
      EXPECT_EQ(r.loaded, m) << mask;
    } else if (ssm < 0.0) {
      EXPECT_EQ(r.status, SagStatus::Unstable) << mask;
    } else {
      EXPECT_NE(r.status, SagStatus::NotConverged) << mask;
    }
    if (r.status == SagStatus::Converged) {
      ++stable;
      EXPECT_LT(r.equilibrium_residual, 1e-9);
      EXPECT_LT(r.rigidity_residual, 1e-9);
      for (int i = 0; i < 6; ++i) {
        if (mask & (1 << i)) {
          EXPECT_EQ(r.forces.col(i).norm(), 0.0);
        }
        EXPECT_GE(r.forces(2, i), 0.0);
      }
    } else {
      ++unstable;
    }
  }
  EXPECT_GE(stable, 22);  // all 6, 5 (6 ways), 4 (15 ways, all with SSM > 0.3 or marginal) ...
  EXPECT_GE(unstable, 22);  // ... fewer than 3 (22 ways)
}

TEST(Sag, LeansOntoALiftedFootThatCatchesIt) {
  // Square stance, foot 0 at (1, 1) lifted 1 cm (three times the sag); the CG at (0.3, 0.3) is outside the triangle of
  // the three touching feet, so the robot leans until foot 0 touches and carries load.
  SagProblem p;
  p.feet.resize(3, 4);
  p.feet << 1, -1, -1, 1, 1, 1, -1, -1, 0.01, 0, 0, 0;
  p.stiffness = Eigen::Matrix3Xd::Constant(3, 4, 1e5);
  p.lift = Eigen::VectorXd::Zero(4);
  p.lift(0) = 0.01;
  p.cg << 0.3, 0.3, 1.0;
  p.mass = 100.0;
  const SagResult r = solve_sag(p);
  ASSERT_EQ(r.status, SagStatus::Converged);
  EXPECT_GT(r.forces(2, 0), 0.0);
  EXPECT_GT(r.compression(0), 0.0);
  EXPECT_LT(r.equilibrium_residual, 1e-9);
  // Feet 0 and 2 lie on the CG's diagonal: foot 2, opposite, carries the least.
  EXPECT_LT(r.forces(2, 2), r.forces(2, 1));
  for (int i = 0; i < 4; ++i) EXPECT_GE(r.forces(2, i), 0.0);
}

TEST(Sag, RotatingTheWholeProblemRotatesTheAnswer) {
  // Slope: gravity, springs, feet and CG all rotated together give the rotated solution.
  SagProblem p = hexapod(3e5, 1e5);
  p.cg << 0.3, -0.2, 1.75;
  const SagResult r0 = solve_sag(p);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.35, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
  SagProblem q = p;
  q.feet = R * p.feet;
  q.cg = R * p.cg;
  q.gravity = R * p.gravity;
  q.spring_frame = R;
  q.body_points = R * p.body_points;
  q.chassis_position = R * p.chassis_position;
  q.chassis_rotation = R;
  const SagResult r1 = solve_sag(q);
  ASSERT_EQ(r1.status, SagStatus::Converged);
  EXPECT_LT((r1.forces - R * r0.forces).norm(), 1e-7 * r0.forces.norm());
  EXPECT_LT((r1.body_points - R * r0.body_points).norm(), 1e-10);
  EXPECT_LT((r1.chassis_rotation - R * r0.chassis_rotation).norm(), 1e-9);
}

TEST(Sag, TooFewFeetIsUnstableAndInvalidInputNamesTheField) {
  SagProblem p = hexapod();
  p.feet = p.feet.leftCols(2).eval();
  p.stiffness = p.stiffness.leftCols(2).eval();
  SagResult r = solve_sag(p);
  EXPECT_EQ(r.status, SagStatus::Unstable);
  EXPECT_TRUE(r.forces.allFinite());
  EXPECT_EQ(std::string(to_string(r.status)), "unstable");

  auto message = [](const SagProblem& bad) {
    return invalid_argument_message([&] { solve_sag(bad); });
  };
  SagProblem bad = hexapod();
  bad.stiffness(2, 1) = 0.0;
  EXPECT_NE(message(bad).find("stiffness(2, 1)"), std::string::npos);
  bad = hexapod();
  bad.feet(0, 3) = std::nan("");
  EXPECT_NE(message(bad).find("feet(0, 3)"), std::string::npos);
  bad = hexapod();
  bad.mass = -2;
  EXPECT_NE(message(bad).find("mass"), std::string::npos);
  bad = hexapod();
  bad.lift = Eigen::VectorXd::Zero(6);
  bad.lift(4) = std::nan("");
  EXPECT_NE(message(bad).find("lift(4)"), std::string::npos);
  bad = hexapod();
  bad.lift = Eigen::VectorXd::Zero(5);
  EXPECT_NE(message(bad).find("lift"), std::string::npos);
  bad = hexapod();
  bad.spring_frame(0, 0) = 2.0;
  EXPECT_NE(message(bad).find("spring_frame"), std::string::npos);
  bad = hexapod();
  bad.gravity.setZero();
  EXPECT_NE(message(bad).find("gravity"), std::string::npos);
  SagOptions opt;
  opt.tolerance = -1;
  EXPECT_NE(invalid_argument_message([&] { solve_sag(hexapod(), opt); }).find("tolerance"),
            std::string::npos);
}

namespace {
// §5.1.2's protocol on synthetic data: all feet down, each of three legs lifted in turn, two
// opposite legs lifted; heights of the six leg-attachment corners "measured" from the model
// with k_true plus Gaussian noise.
std::vector<CalibrationStance> synthetic_stances(double k_true, double noise, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, noise);
  std::vector<std::vector<int>> lifted{{}, {0}, {2}, {4}, {1, 4}};
  std::vector<CalibrationStance> out;
  for (const auto& legs : lifted) {
    CalibrationStance st;
    st.problem = hexapod(1.0, 1.0);  // relative stiffness: one constant for every spring
    st.problem.cg << 0.1, -0.05, 1.75;
    st.problem.lift = Eigen::VectorXd::Zero(6);
    for (int leg : legs) {
      st.problem.feet(2, leg) += 0.2;
      st.problem.lift(leg) = 0.2;
    }
    SagProblem truth = st.problem;
    truth.stiffness *= k_true;
    const SagResult r = solve_sag(truth);
    EXPECT_EQ(r.status, SagStatus::Converged);
    st.measured_heights = r.body_points.row(2).transpose();
    for (Eigen::Index j = 0; j < st.measured_heights.size(); ++j) {
      st.measured_heights(j) += gauss(rng);
    }
    out.push_back(st);
  }
  return out;
}
}  // namespace

TEST(SagCalibration, RecoversTheSpringConstant) {
  const double k_true = 8e4;
  // Noise-free: the grid (log step 16 %) brackets it, Brent pins it.
  CalibrationResult r = calibrate_spring_constant(synthetic_stances(k_true, 0.0, 1));
  EXPECT_NEAR(r.k_grid, k_true, 0.09 * k_true);
  EXPECT_NEAR(r.k, k_true, 1e-4 * k_true);
  EXPECT_LT(r.mean_error, 1e-7);
  EXPECT_LE(r.mean_error, r.error_grid);
  // 2 mm of measurement noise on ~2 cm of sag (the paper's errors are ~1 cm on SDM-B's larger
  // sag): within 10 %, and the residual error is the noise level.
  for (unsigned seed : {2u, 3u, 4u}) {
    r = calibrate_spring_constant(synthetic_stances(k_true, 0.002, seed));
    EXPECT_NEAR(r.k, k_true, 0.1 * k_true) << seed;
    EXPECT_GT(r.mean_error, 0.0008);
    EXPECT_LT(r.mean_error, 0.003);
    EXPECT_EQ(r.grid_k.size(), 61);
  }
}

TEST(SagCalibration, InvalidInputNamesTheField) {
  std::vector<CalibrationStance> st = synthetic_stances(8e4, 0.0, 1);
  st[1].measured_heights.resize(3);
  EXPECT_NE(invalid_argument_message([&] { calibrate_spring_constant(st); })
                .find("stances[1].measured_heights"),
            std::string::npos);
  CalibrationOptions opt;
  opt.k_max = 0.5 * opt.k_min;
  EXPECT_NE(invalid_argument_message([&] { calibrate_spring_constant(synthetic_stances(8e4, 0, 1), opt); })
                .find("k_max"),
            std::string::npos);
  EXPECT_NE(invalid_argument_message([&] { calibrate_spring_constant({}); }).find("stances"),
            std::string::npos);
}

TEST(SagCalibration, RecoversPerFootConstants) {
  // §5.1.4: tyre pressures within ±12.5 %; the per-foot fit recovers each constant from the
  // same protocol (noise-free), starting from the single best constant.
  const Eigen::VectorXd truth = (Eigen::VectorXd(6) << 1.0, 1.1, 0.9, 1.125, 0.875, 1.05).finished() * 8e4;
  std::vector<CalibrationStance> st = synthetic_stances(1.0, 0.0, 1);
  for (CalibrationStance& s : st) {  // re-measure with the per-foot constants
    SagProblem p = s.problem;
    for (int i = 0; i < 6; ++i) p.stiffness.col(i) *= truth(i);
    s.measured_heights = solve_sag(p).body_points.row(2).transpose();
  }
  const CalibrationResult single = calibrate_spring_constant(st);
  EXPECT_GT(single.mean_error, 1e-5);  // one constant cannot explain unequal tyres
  const PerFootCalibrationResult r = calibrate_per_foot_constants(st, single.k);
  EXPECT_GE(r.lm_status, 1);
  EXPECT_LE(r.lm_status, 4);
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(r.k(i), truth(i), 1e-4 * truth(i)) << i;
  EXPECT_LT(r.mean_error, 1e-9);
}
