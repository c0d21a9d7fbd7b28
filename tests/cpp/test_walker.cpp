// The wheel-on-leg walker (seed 003 §2.3, §5.3): kinematics against an independent closed-form
// IK of the SDM-B leg (hip yaw, planar hip–knee pair, XYX wrist), Jacobians and torques against
// finite differences of the forward kinematics and of the potential energy, and a single-link
// case in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "ernest/walker/leg_ik.hpp"
#include "test_util.hpp"

using namespace ernest::walker;
using ernest::testing::invalid_argument_message;

namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::VectorXd random_q(const WalkerModel& m, std::mt19937_64& rng, double shrink = 0.9) {
  Eigen::VectorXd q(m.joints_per_leg());
  for (int i = 0; i < q.size(); ++i) {
    const double c = 0.5 * (m.lower_limits()[i] + m.upper_limits()[i]);
    const double h = 0.5 * shrink * (m.upper_limits()[i] - m.lower_limits()[i]);
    q[i] = std::uniform_real_distribution<double>(c - h, c + h)(rng);
  }
  return q;
}

double wrap(double a) { return std::remainder(a, 2.0 * kPi); }

// Closed-form IK of an SDM-B leg on leg 0 (mount on +x, not rotated): every solution of the eight
// branches (yaw ±, knee ±, wrist ±) that lies inside the joint limits. Written from the geometry
// of sdm_b_parameters(), independently of the numerical solver.
std::vector<Eigen::VectorXd> analytic_ik(const WalkerModel& m, const Eigen::Isometry3d& foot) {
  const WalkerParameters& p = m.params();
  const double a1 = p.joints[1].offset.x(), l1 = p.joints[2].offset.x(), l2 = p.joints[4].offset.x();
  const double d = p.foot_offset.x();
  const Eigen::Vector3d ankle = foot.translation() + d * foot.linear().col(2) - m.hip_mount(0).translation();
  const Eigen::Matrix3d r6 = foot.linear() * p.foot_rotation.transpose();
  std::vector<Eigen::VectorXd> out;
  for (int yaw = 0; yaw < 2; ++yaw) {
    const double q1 = std::atan2(ankle.y(), ankle.x()) + yaw * kPi;
    const double r = ankle.x() * std::cos(q1) + ankle.y() * std::sin(q1) - a1, z = ankle.z();
    const double c3 = (r * r + z * z - l1 * l1 - l2 * l2) / (2 * l1 * l2);
    if (std::abs(c3) > 1) continue;
    for (int knee = -1; knee <= 1; knee += 2) {
      const double q3 = knee * std::acos(c3);
      const double q2 = std::atan2(-z, r) - std::atan2(l2 * std::sin(q3), l1 + l2 * std::cos(q3));
      const Eigen::Matrix3d r3 = (Eigen::AngleAxisd(q1, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(q2 + q3, Eigen::Vector3d::UnitY()))
                                     .toRotationMatrix();
      const Eigen::Matrix3d w = r3.transpose() * r6;  // = Rx(q4) Ry(q5) Rx(q6)
      for (int flip = -1; flip <= 1; flip += 2) {
        const double q5 = flip * std::acos(std::clamp(w(0, 0), -1.0, 1.0));
        const double s5 = std::sin(q5);
        const double q4 = std::atan2(w(1, 0) / s5, -w(2, 0) / s5);
        const double q6 = std::atan2(w(0, 1) / s5, w(0, 2) / s5);
        Eigen::VectorXd q(6);
        q << wrap(q1), wrap(q2), wrap(q3), wrap(q4), q5, wrap(q6);
        if (m.within_limits(q)) out.push_back(q);
      }
    }
  }
  return out;
}

void expect_pose_near(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double tol) {
  EXPECT_LT((a.translation() - b.translation()).norm(), tol);
  EXPECT_LT((a.linear() - b.linear()).norm(), tol);
}

}  // namespace

TEST(WalkerParameters, PresetsValidAndInvalidFieldsNamed) {
  EXPECT_NO_THROW(sdm_b_parameters().validate());
  EXPECT_NO_THROW(t12_parameters().validate());
  EXPECT_NEAR(sdm_b_parameters().total_mass(), 850.0, 1e-9);
  auto p = sdm_b_parameters();
  p.wheel_radius = -0.1;
  EXPECT_NE(invalid_argument_message([&] { p.validate(); }).find("wheel_radius"), std::string::npos);
  p = sdm_b_parameters();
  p.joints[2].torque_limit = std::nan("");
  EXPECT_NE(invalid_argument_message([&] { p.validate(); }).find("joints[2].torque_limit"),
            std::string::npos);
  p = sdm_b_parameters();
  p.joints[1].upper = p.joints[1].lower - 0.1;
  EXPECT_NE(invalid_argument_message([&] { p.validate(); }).find("joints[1].upper"), std::string::npos);
  p = sdm_b_parameters();
  p.standard_height = 5.0;  // legs too short: the standard stance cannot be built
  EXPECT_NE(invalid_argument_message([&] { WalkerModel m(p); }).find("unreachable"), std::string::npos);
}

TEST(WalkerModel, StandardStanceIsTheDocumentedPose) {
  for (const auto& params : {sdm_b_parameters(), t12_parameters()}) {
    const WalkerModel m(params);
    const Eigen::Isometry3d body = m.standard_body_pose();
    const Eigen::Matrix3Xd c = m.contact_points(body, m.standard_configuration());
    EXPECT_NEAR(body.translation().z(), params.standard_height, 1e-12);  // §5.1.4: 1.75 m / 2.15 m
    for (int k = 0; k < m.legs(); ++k) {
      EXPECT_NEAR(c(2, k), 0.0, 1e-7);  // every wheel on the ground
      const double a = 2 * kPi * k / m.legs();
      EXPECT_NEAR(c(0, k), params.standard_foot_radius * std::cos(a), 1e-7);
      EXPECT_NEAR(c(1, k), params.standard_foot_radius * std::sin(a), 1e-7);
      EXPECT_TRUE(m.within_limits(m.standard_configuration().col(k)));
    }
    const Eigen::Vector3d com = m.center_of_mass(body, m.standard_configuration());
    EXPECT_NEAR(com.x(), 0.0, 1e-9);
    EXPECT_NEAR(com.y(), 0.0, 1e-9);
    EXPECT_GT(com.z(), 0.0);
  }
}

TEST(WalkerIk, RoundTripsMatchTheClosedFormSolutions) {
  const WalkerModel m(sdm_b_parameters());
  IkOptions o;
  o.seeds = 48;
  LegIk ik(m, o);
  std::mt19937_64 rng(7);
  int compared = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const Eigen::VectorXd q = random_q(m, rng);
    const Eigen::Isometry3d target = m.foot_pose(0, q);
    const IkResult r = ik.solve(0, target, m.standard_configuration().col(0));
    ASSERT_EQ(r.status, IkStatus::kSolved);
    for (const auto& s : r.solutions) {
      EXPECT_TRUE(m.within_limits(s));
      expect_pose_near(m.foot_pose(0, s), target, 1e-6);
    }
    // Every numerical solution is one of the closed-form ones, and every closed-form solution
    // well inside the limits (0.05 rad) is found.
    const auto exact = analytic_ik(m, target);
    ASSERT_FALSE(exact.empty());
    auto matches = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
      for (int i = 0; i < a.size(); ++i)
        if (std::abs(wrap(a[i] - b[i])) > 1e-5) return false;
      return true;
    };
    for (const auto& s : r.solutions)
      EXPECT_TRUE(std::any_of(exact.begin(), exact.end(), [&](auto& e) { return matches(s, e); }));
    for (const auto& e : exact) {
      if (((m.upper_limits() - e).array() < 0.05).any() || ((e - m.lower_limits()).array() < 0.05).any())
        continue;
      ++compared;
      EXPECT_TRUE(std::any_of(r.solutions.begin(), r.solutions.end(),
                              [&](auto& s) { return matches(s, e); }))
          << "missed closed-form solution " << e.transpose();
    }
  }
  EXPECT_GT(compared, 40);
}

TEST(WalkerIk, UnreachableTargetsAreReportedWithTheClosestApproach) {
  const WalkerModel m(sdm_b_parameters());
  LegIk ik(m);
  // Far beyond the leg's reach: 5 m below the hip.
  Eigen::Isometry3d far = upright_foot_pose(m, Eigen::Vector3d(2.0, 0.0, -5.0), 0.0);
  IkResult r = ik.solve(0, far, m.standard_configuration().col(0));
  EXPECT_EQ(r.status, IkStatus::kUnreachable);
  EXPECT_TRUE(r.solutions.empty());
  // Reach from the hip pitch axis to the wheel centre is at most thigh + shank + foot = 1.95 m.
  const Eigen::Vector3d hip = m.hip_mount(0).translation() + Eigen::Vector3d(0.2, 0, 0);
  EXPECT_GE(r.position_error, (far.translation() - hip).norm() - 1.95 - 1e-6);
  EXPECT_TRUE(m.within_limits(r.closest));
  // Geometrically reachable but only outside the limits: the standard contact with the wheel
  // turned round needs the ankle roll or knee roll at 180° (limits ±175°) or the yaw flipped.
  const Eigen::Vector3d c(m.params().standard_foot_radius, 0.0, -m.params().standard_height);
  const Eigen::Isometry3d reversed = upright_foot_pose(m, c, kPi);
  r = ik.solve(0, reversed, m.standard_configuration().col(0));
  EXPECT_EQ(r.status, IkStatus::kUnreachable);
  EXPECT_TRUE(m.within_limits(r.closest));
  // With the ankle roll free over a full turn the same target is solved.
  WalkerParameters wide = sdm_b_parameters();
  wide.joints[5].lower = -kPi;
  wide.joints[5].upper = kPi;
  const WalkerModel mw(wide);
  LegIk ikw(mw);
  r = ikw.solve(0, reversed, mw.standard_configuration().col(0));
  ASSERT_EQ(r.status, IkStatus::kSolved);
  expect_pose_near(mw.foot_pose(0, r.solutions.front()), reversed, 1e-6);
}

TEST(WalkerIk, SevenJointLegAndEveryLeg) {
  const WalkerModel m(t12_parameters());
  EXPECT_EQ(m.joints_per_leg(), 7);
  LegIk ik(m);
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 12; ++trial) {
    const int leg = trial % 6;
    const Eigen::VectorXd q = random_q(m, rng, 0.6);
    const Eigen::Isometry3d target = m.foot_pose(leg, q);
    const IkResult r = ik.solve(leg, target, m.standard_configuration().col(leg));
    ASSERT_EQ(r.status, IkStatus::kSolved);
    for (const auto& s : r.solutions) {
      EXPECT_TRUE(m.within_limits(s));
      expect_pose_near(m.foot_pose(leg, s), target, 1e-6);
    }
  }
}

TEST(WalkerModel, JacobiansMatchFiniteDifferences) {
  for (const auto& params : {sdm_b_parameters(), t12_parameters()}) {
    const WalkerModel m(params);
    const int n = m.joints_per_leg();
    LegWorkspace ws(m);
    Eigen::Matrix3Xd Jc(3, n);
    Eigen::MatrixXd Jf(6, n);
    std::mt19937_64 rng(11);
    for (int trial = 0; trial < 10; ++trial) {
      const int leg = trial % m.legs();
      const Eigen::VectorXd q = random_q(m, rng);
      m.forward(leg, q, ws);
      m.contact_jacobian(ws, Jc);
      m.foot_jacobian(ws, Jf);
      const double h = 1e-6;
      for (int i = 0; i < n; ++i) {
        Eigen::VectorXd qp = q, qm = q;
        qp[i] += h;
        qm[i] -= h;
        const Eigen::Vector3d dc = (m.contact_point(leg, qp) - m.contact_point(leg, qm)) / (2 * h);
        EXPECT_LT((dc - Jc.col(i)).norm(), 1e-7);
        const Eigen::Isometry3d fp = m.foot_pose(leg, qp), fm = m.foot_pose(leg, qm);
        EXPECT_LT(((fp.translation() - fm.translation()) / (2 * h) - Jf.block<3, 1>(0, i)).norm(), 1e-7);
        // Angular velocity from dR/dq R^T (skew-symmetric).
        const Eigen::Matrix3d W = (fp.linear() - fm.linear()) / (2 * h) * m.foot_pose(leg, q).linear().transpose();
        const Eigen::Vector3d w(W(2, 1), W(0, 2), W(1, 0));
        EXPECT_LT((w - Jf.block<3, 1>(3, i)).norm(), 1e-7);
      }
    }
  }
}

TEST(WalkerModel, TorquesEqualVirtualWork) {
  const WalkerModel m(sdm_b_parameters());
  const int n = m.joints_per_leg();
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 10; ++trial) {
    const int leg = trial % 6;
    const Eigen::VectorXd q = random_q(m, rng);
    const Eigen::Matrix3d body =
        (Eigen::AngleAxisd(0.2 * trial, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    const Eigen::Vector3d g = m.gravity_in_body(body);
    const Eigen::Vector3d reaction(300.0 * trial - 1000.0, 150.0, 2500.0);
    const Eigen::VectorXd tau = m.joint_torques(leg, q, reaction, body);
    // Potential energy of the leg's links, V = -sum m_j g·c_j (body frame), by finite differences.
    auto potential = [&](const Eigen::VectorXd& qq) {
      LegWorkspace ws(m);
      m.forward(leg, qq, ws);
      double v = 0.0;
      for (int j = 0; j < n; ++j) v -= m.params().joints[j].mass * g.dot(ws.link_com.col(j));
      return v;
    };
    const double h = 1e-6;
    for (int i = 0; i < n; ++i) {
      Eigen::VectorXd qp = q, qm = q;
      qp[i] += h;
      qm[i] -= h;
      const double dv = (potential(qp) - potential(qm)) / (2 * h);
      const double work = -reaction.dot(m.contact_point(leg, qp) - m.contact_point(leg, qm)) / (2 * h);
      EXPECT_NEAR(tau[i], dv + work, 1e-5 * (1.0 + std::abs(tau[i])));
    }
  }
}

TEST(WalkerModel, SingleLinkClosedForm) {
  // One pitch joint, a uniform link of length l with mass m, the wheel at its end:
  // g(q) = -m g (l/2) cos q; a vertical reaction F at the contact (l + r along the link) adds
  // F (l + r) cos q; the limit 1000 N m gives the saturation fraction.
  WalkerParameters p = sdm_b_parameters();
  const double l = 1.2, mass = 30.0, r = p.wheel_radius, limit = 1000.0;
  JointSpec j;
  j.name = "pitch";
  j.axis = Eigen::Vector3d::UnitY();
  j.lower = -1.5;
  j.upper = 1.6;
  j.torque_limit = limit;
  j.mass = mass;
  j.com = Eigen::Vector3d(l / 2, 0, 0);
  p.joints = {j};
  p.foot_offset = Eigen::Vector3d(l, 0, 0);
  // Standard stance: the link hanging straight down (the only pose with an upright wheel).
  p.standard_height = l + r;
  p.standard_foot_radius = p.hip_radius;
  const WalkerModel m(p);
  EXPECT_NEAR(m.standard_configuration()(0, 0), kPi / 2, 1e-6);
  for (double q : {-1.0, 0.0, 0.3, 1.2}) {
    Eigen::VectorXd qv(1);
    qv << q;
    const double F = 800.0;
    const Eigen::VectorXd tau = m.joint_torques(2, qv, Eigen::Vector3d(0, 0, F));
    const double expected = -mass * p.gravity * (l / 2) * std::cos(q) + F * (l + r) * std::cos(q);
    EXPECT_NEAR(tau[0], expected, 1e-9);
    EXPECT_NEAR(m.saturation(tau)[0], std::abs(expected) / limit, 1e-12);
    EXPECT_NEAR(m.margin_to_saturation(tau), 1.0 - std::abs(expected) / limit, 1e-12);
  }
}

TEST(WalkerModel, CollisionCapsulesFollowTheJoints) {
  const WalkerModel m(sdm_b_parameters());
  const Eigen::VectorXd q = m.standard_configuration().col(3);
  const auto caps = m.leg_capsules(3, q);
  ASSERT_EQ(caps.size(), 7u);  // six links and the wheel
  LegWorkspace ws(m);
  m.forward(3, q, ws);
  // The thigh runs from the hip pitch joint to the knee.
  EXPECT_LT((caps[1].p0 - ws.joint_position.col(1)).norm(), 1e-12);
  EXPECT_LT((caps[1].p1 - ws.joint_position.col(2)).norm(), 1e-12);
  // Standard stance: only the wheel reaches the ground (its lowest point at z = 0).
  const auto all = m.capsules(m.standard_body_pose(), m.standard_configuration());
  ASSERT_EQ(all.size(), 42u);
  for (const auto& c : all) {
    const double low = std::min(c.p0.z(), c.p1.z()) - c.radius;
    if (c.link == -1)
      EXPECT_NEAR(low, 0.0, 1e-7);
    else
      EXPECT_GT(low, 0.1);
  }
}

TEST(WalkerModel, BadInputsNameTheField) {
  const WalkerModel m(sdm_b_parameters());
  Eigen::VectorXd q = m.standard_configuration().col(0);
  EXPECT_NE(invalid_argument_message([&] { m.foot_pose(6, q); }).find("leg"), std::string::npos);
  EXPECT_NE(invalid_argument_message([&] { m.foot_pose(0, Eigen::VectorXd::Zero(5)); }).find("expected 6"),
            std::string::npos);
  q[2] = std::nan("");
  EXPECT_NE(invalid_argument_message([&] { m.contact_point(0, q); }).find("knee_pitch"), std::string::npos);
  IkOptions o;
  o.seeds = 0;
  EXPECT_NE(invalid_argument_message([&] { LegIk ik(m, o); }).find("IkOptions.seeds"), std::string::npos);
  LegIk ik(m);
  Eigen::Isometry3d t = m.foot_pose(0, m.standard_configuration().col(0));
  t.linear() *= 2.0;
  EXPECT_NE(invalid_argument_message([&] { ik.solve(0, t, m.standard_configuration().col(0)); })
                .find("rotation"),
            std::string::npos);
}
