#include "ernest/walker/walker_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "ernest/common/validation.hpp"
#include "ernest/walker/leg_ik.hpp"

namespace ernest::walker {

namespace {
constexpr double kPi = 3.14159265358979323846;

// Rodrigues: rotation by angle q about the unit axis a.
Eigen::Matrix3d axis_rotation(const Eigen::Vector3d& a, double q) {
  const double c = std::cos(q), s = std::sin(q), v = 1.0 - c;
  Eigen::Matrix3d r;
  r << c + a.x() * a.x() * v, a.x() * a.y() * v - a.z() * s, a.x() * a.z() * v + a.y() * s,
      a.y() * a.x() * v + a.z() * s, c + a.y() * a.y() * v, a.y() * a.z() * v - a.x() * s,
      a.z() * a.x() * v - a.y() * s, a.z() * a.y() * v + a.x() * s, c + a.z() * a.z() * v;
  return r;
}
}  // namespace

LegWorkspace::LegWorkspace(const WalkerModel& model) {
  const int n = model.joints_per_leg();
  joint_position.setZero(3, n);
  joint_axis.setZero(3, n);
  link_com.setZero(3, n);
  rotation.setZero(3, 3 * n);
  foot_rotation.setIdentity();
  wheel_centre.setZero();
  contact.setZero();
}

WalkerModel::WalkerModel(const WalkerParameters& params) : p_(params) {
  p_.validate();
  n_ = p_.joints_per_leg();
  lower_.resize(n_);
  upper_.resize(n_);
  torque_limit_.resize(n_);
  for (int i = 0; i < n_; ++i) {
    lower_[i] = p_.joints[i].lower;
    upper_[i] = p_.joints[i].upper;
    torque_limit_[i] = p_.joints[i].torque_limit;
  }
  for (int k = 0; k < p_.legs; ++k) {
    const double a = 2.0 * kPi * k / p_.legs;
    Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
    m.linear() = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    m.translation() = p_.hip_radius * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
    mounts_.push_back(m);
  }
  // Standard stance: leg 0's foot on the +x axis, wheel rolling radially, hips standard_height
  // above the ground; solved once and copied to every leg (the legs are identical and the mounts
  // rotationally symmetric). Seed: knee up, foot link vertical (the spider stance of ATHLETE).
  const Eigen::Vector3d contact(p_.standard_foot_radius, 0.0, -p_.standard_height);
  LegIk ik(*this);
  Eigen::VectorXd seed = Eigen::VectorXd::Zero(n_);
  for (int i = 0; i < n_; ++i) {
    const std::string& name = p_.joints[i].name;
    if (name == "hip_pitch") seed[i] = 0.4;
    if (name == "knee_pitch") seed[i] = 1.5;
    if (name == "ankle_pitch") seed[i] = -0.3;
    seed[i] = std::min(std::max(seed[i], lower_[i]), upper_[i]);
  }
  const IkResult r = ik.solve(0, upright_foot_pose(*this, contact, 0.0), seed);
  require(r.status == IkStatus::kSolved,
          "WalkerParameters: the standard stance (standard_height = " +
              std::to_string(p_.standard_height) + ", standard_foot_radius = " +
              std::to_string(p_.standard_foot_radius) + ") is unreachable");
  q_standard_ = r.solutions.front().replicate(1, p_.legs);
}

const Eigen::Isometry3d& WalkerModel::hip_mount(int leg) const {
  check_leg(leg);
  return mounts_[leg];
}

Eigen::Isometry3d WalkerModel::standard_body_pose() const {
  Eigen::Isometry3d b = Eigen::Isometry3d::Identity();
  b.translation() = Eigen::Vector3d(0.0, 0.0, p_.standard_height);
  return b;
}

void WalkerModel::forward(int leg, const Eigen::Ref<const Eigen::VectorXd>& q,
                          LegWorkspace& ws) const {
  const Eigen::Isometry3d& m = mounts_[leg];
  Eigen::Matrix3d r = m.linear();
  Eigen::Vector3d p = m.translation();
  for (int i = 0; i < n_; ++i) {
    const JointSpec& j = p_.joints[i];
    p += r * j.offset;
    ws.joint_position.col(i) = p;
    ws.joint_axis.col(i) = r * j.axis;
    r = r * axis_rotation(j.axis, q[i]);
    ws.rotation.block<3, 3>(0, 3 * i) = r;
    ws.link_com.col(i) = p + r * j.com;
  }
  ws.wheel_centre = p + r * p_.foot_offset;
  ws.foot_rotation = r * p_.foot_rotation;
  ws.contact = ws.wheel_centre - p_.wheel_radius * ws.foot_rotation.col(2);
}

Eigen::Isometry3d WalkerModel::foot_pose(int leg, const Eigen::Ref<const Eigen::VectorXd>& q) const {
  check_leg(leg);
  check_q(q);
  LegWorkspace ws(*this);
  forward(leg, q, ws);
  Eigen::Isometry3d f = Eigen::Isometry3d::Identity();
  f.linear() = ws.foot_rotation;
  f.translation() = ws.wheel_centre;
  return f;
}

Eigen::Vector3d WalkerModel::contact_point(int leg, const Eigen::Ref<const Eigen::VectorXd>& q) const {
  check_leg(leg);
  check_q(q);
  LegWorkspace ws(*this);
  forward(leg, q, ws);
  return ws.contact;
}

void WalkerModel::contact_jacobian(const LegWorkspace& ws, Eigen::Ref<Eigen::Matrix3Xd> J) const {
  for (int i = 0; i < n_; ++i)
    J.col(i) = ws.joint_axis.col(i).cross(ws.contact - ws.joint_position.col(i));
}

void WalkerModel::foot_jacobian(const LegWorkspace& ws, Eigen::Ref<Eigen::MatrixXd> J) const {
  for (int i = 0; i < n_; ++i) {
    J.block<3, 1>(0, i) = ws.joint_axis.col(i).cross(ws.wheel_centre - ws.joint_position.col(i));
    J.block<3, 1>(3, i) = ws.joint_axis.col(i);
  }
}

void WalkerModel::gravity_torques(const LegWorkspace& ws, const Eigen::Vector3d& gravity_body,
                                  Eigen::Ref<Eigen::VectorXd> tau) const {
  // dV/dq_i = -sum_{j >= i} m_j g · (axis_i × (c_j − p_i)) = -axis_i · ((C_i − M_i p_i) × g),
  // with M_i, C_i the mass and first moment of the links beyond joint i (a backward sweep).
  double mass = 0.0;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  for (int i = n_ - 1; i >= 0; --i) {
    mass += p_.joints[i].mass;
    moment += p_.joints[i].mass * ws.link_com.col(i);
    tau[i] = -ws.joint_axis.col(i).dot((moment - mass * ws.joint_position.col(i)).cross(gravity_body));
  }
}

void WalkerModel::joint_torques(const LegWorkspace& ws, const Eigen::Vector3d& reaction,
                                const Eigen::Vector3d& gravity_body,
                                Eigen::Ref<Eigen::VectorXd> tau) const {
  gravity_torques(ws, gravity_body, tau);
  const Eigen::Vector3d f = -reaction;  // the force the wheel applies to the ground
  for (int i = 0; i < n_; ++i)
    tau[i] += ws.joint_axis.col(i).cross(ws.contact - ws.joint_position.col(i)).dot(f);
}

Eigen::VectorXd WalkerModel::joint_torques(int leg, const Eigen::Ref<const Eigen::VectorXd>& q,
                                           const Eigen::Vector3d& reaction,
                                           const Eigen::Matrix3d& body_rotation) const {
  check_leg(leg);
  check_q(q);
  for (int k = 0; k < 3; ++k) require_finite("joint_torques", "reaction", reaction[k]);
  LegWorkspace ws(*this);
  forward(leg, q, ws);
  Eigen::VectorXd tau(n_);
  joint_torques(ws, reaction, gravity_in_body(body_rotation), tau);
  return tau;
}

Eigen::VectorXd WalkerModel::saturation(const Eigen::Ref<const Eigen::VectorXd>& tau) const {
  require(tau.size() == n_, "saturation: tau has " + std::to_string(tau.size()) +
                                " entries, expected " + std::to_string(n_));
  return tau.cwiseAbs().cwiseQuotient(torque_limit_);
}

double WalkerModel::margin_to_saturation(const Eigen::Ref<const Eigen::VectorXd>& tau) const {
  return 1.0 - saturation(tau).maxCoeff();
}

Eigen::Vector3d WalkerModel::gravity_in_body(const Eigen::Matrix3d& body_rotation) const {
  require(body_rotation.allFinite() &&
              (body_rotation.transpose() * body_rotation - Eigen::Matrix3d::Identity()).norm() < 1e-6,
          "body_rotation must be a finite rotation matrix");
  return body_rotation.transpose() * Eigen::Vector3d(0.0, 0.0, -p_.gravity);
}

Eigen::Vector3d WalkerModel::center_of_mass(const Eigen::Isometry3d& body,
                                            const Eigen::Ref<const Eigen::MatrixXd>& q) const {
  check_configuration(q);
  LegWorkspace ws(*this);
  Eigen::Vector3d moment = p_.chassis_mass * p_.chassis_com;
  double mass = p_.chassis_mass;
  for (int k = 0; k < p_.legs; ++k) {
    forward(k, q.col(k), ws);
    for (int i = 0; i < n_; ++i) {
      moment += p_.joints[i].mass * ws.link_com.col(i);
      mass += p_.joints[i].mass;
    }
  }
  return body * (moment / mass);
}

Eigen::Matrix3Xd WalkerModel::contact_points(const Eigen::Isometry3d& body,
                                             const Eigen::Ref<const Eigen::MatrixXd>& q) const {
  check_configuration(q);
  LegWorkspace ws(*this);
  Eigen::Matrix3Xd c(3, p_.legs);
  for (int k = 0; k < p_.legs; ++k) {
    forward(k, q.col(k), ws);
    c.col(k) = body * ws.contact;
  }
  return c;
}

std::vector<LinkCapsule> WalkerModel::leg_capsules(int leg,
                                                   const Eigen::Ref<const Eigen::VectorXd>& q) const {
  check_leg(leg);
  check_q(q);
  LegWorkspace ws(*this);
  forward(leg, q, ws);
  std::vector<LinkCapsule> out;
  for (int i = 0; i < n_; ++i) {
    const Capsule& g = p_.joints[i].geometry;
    if (g.radius <= 0.0) continue;
    const auto r = ws.rotation.block<3, 3>(0, 3 * i);
    out.push_back({leg, i, ws.joint_position.col(i) + r * g.p0, ws.joint_position.col(i) + r * g.p1,
                   g.radius});
  }
  // The wheel: a capsule along the axle (radius = wheel radius, ends inset so its length is the
  // tyre width at the centre plane).
  const Eigen::Vector3d axle = ws.foot_rotation.col(1);
  const double half = std::max(0.0, 0.5 * p_.wheel_width);
  out.push_back({leg, -1, ws.wheel_centre - half * axle, ws.wheel_centre + half * axle,
                 p_.wheel_radius});
  return out;
}

std::vector<LinkCapsule> WalkerModel::capsules(const Eigen::Isometry3d& body,
                                               const Eigen::Ref<const Eigen::MatrixXd>& q) const {
  check_configuration(q);
  std::vector<LinkCapsule> out;
  for (int k = 0; k < p_.legs; ++k)
    for (LinkCapsule c : leg_capsules(k, q.col(k))) {
      c.p0 = body * c.p0;
      c.p1 = body * c.p1;
      out.push_back(c);
    }
  return out;
}

void WalkerModel::check_leg(int leg) const {
  require(leg >= 0 && leg < p_.legs,
          "leg = " + std::to_string(leg) + " is outside [0, " + std::to_string(p_.legs - 1) + "]");
}

void WalkerModel::check_q(const Eigen::Ref<const Eigen::VectorXd>& q, const char* field) const {
  require(q.size() == n_, std::string(field) + " has " + std::to_string(q.size()) +
                              " entries, expected " + std::to_string(n_) + " (joints per leg)");
  for (int i = 0; i < n_; ++i) require_finite(field, p_.joints[i].name.c_str(), q[i]);
}

void WalkerModel::check_configuration(const Eigen::Ref<const Eigen::MatrixXd>& q,
                                      const char* field) const {
  require(q.rows() == n_ && q.cols() == p_.legs,
          std::string(field) + " has shape (" + std::to_string(q.rows()) + ", " +
              std::to_string(q.cols()) + "), expected (joints per leg, legs) = (" +
              std::to_string(n_) + ", " + std::to_string(p_.legs) + ")");
  require(q.allFinite(), std::string(field) + " contains a value that is not finite");
}

bool WalkerModel::within_limits(const Eigen::Ref<const Eigen::VectorXd>& q, double tolerance) const {
  check_q(q);
  return ((q - lower_).array() >= -tolerance).all() && ((upper_ - q).array() >= -tolerance).all();
}

Eigen::Isometry3d upright_foot_pose(const WalkerModel& model, const Eigen::Vector3d& contact,
                                    double heading, const Eigen::Vector3d& up) {
  require(contact.allFinite(), "upright_foot_pose: contact is not finite");
  require(std::isfinite(heading), "upright_foot_pose: heading is not finite");
  require(up.allFinite() && up.norm() > 1e-12, "upright_foot_pose: up must be a finite non-zero vector");
  const Eigen::Vector3d z = up.normalized();
  // Rolling direction: heading measured about z from the projection of the body x axis.
  Eigen::Vector3d x0 = Eigen::Vector3d::UnitX() - z.x() * z;
  if (x0.norm() < 1e-6) x0 = Eigen::Vector3d::UnitY() - z.y() * z;
  x0.normalize();
  const Eigen::Vector3d x = Eigen::AngleAxisd(heading, z) * x0;
  Eigen::Isometry3d f = Eigen::Isometry3d::Identity();
  f.linear().col(0) = x;
  f.linear().col(1) = z.cross(x);
  f.linear().col(2) = z;
  f.translation() = contact + model.params().wheel_radius * z;
  return f;
}

}  // namespace ernest::walker
