#include "ernest/walker/walker_parameters.hpp"

#include <cmath>
#include <string>

#include "ernest/common/validation.hpp"

namespace ernest::walker {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// A slender rod of mass m and length l along x: principal inertias about its CoM.
Eigen::Vector3d rod_inertia(double m, double l, double r) {
  const double axial = 0.5 * m * r * r;
  const double transverse = m * (3.0 * r * r + l * l) / 12.0;
  return {axial, transverse, transverse};
}
// A compact body (actuator, hub) as a solid sphere of radius r.
Eigen::Vector3d sphere_inertia(double m, double r) {
  return Eigen::Vector3d::Constant(0.4 * m * r * r);
}

JointSpec joint(const char* name, Eigen::Vector3d offset, Eigen::Vector3d axis, double lower_deg,
                double upper_deg, double torque_limit, double mass, Eigen::Vector3d com,
                Eigen::Vector3d inertia, Capsule geometry) {
  JointSpec j;
  j.name = name;
  j.offset = offset;
  j.axis = axis;
  j.lower = lower_deg * kDeg;
  j.upper = upper_deg * kDeg;
  j.torque_limit = torque_limit;
  j.mass = mass;
  j.com = com;
  j.inertia = inertia;
  j.geometry = geometry;
  return j;
}

Capsule capsule_x(double length, double radius) {
  return {Eigen::Vector3d::Zero(), Eigen::Vector3d(length, 0, 0), radius};
}

// z_F = -x (back up the leg), y_F = y (axle), x_F = y_F × z_F = z.
Eigen::Matrix3d foot_axes() {
  Eigen::Matrix3d r;
  r.col(0) = Eigen::Vector3d::UnitZ();
  r.col(1) = Eigen::Vector3d::UnitY();
  r.col(2) = -Eigen::Vector3d::UnitX();
  return r;
}

}  // namespace

double WalkerParameters::total_mass() const {
  double m = chassis_mass;
  for (const auto& j : joints) m += legs * j.mass;
  return m;
}

void WalkerParameters::validate() const {
  const char* o = "WalkerParameters";
  require(legs >= 1 && legs <= 12,
          std::string(o) + ".legs = " + std::to_string(legs) + " is outside [1, 12]");
  require(!joints.empty() && joints.size() <= 12,
          std::string(o) + ".joints has " + std::to_string(joints.size()) +
              " entries; a leg needs 1 to 12 joints");
  require_in_range(o, "hip_radius", hip_radius, 0.0, 100.0);
  require_positive(o, "chassis_mass", chassis_mass);
  for (int k = 0; k < 3; ++k) {
    require_finite(o, "chassis_com", chassis_com[k]);
    require_in_range(o, "chassis_inertia", chassis_inertia[k], 0.0, kInf);
    require_finite(o, "foot_offset", foot_offset[k]);
  }
  require_in_range(o, "chassis_collision_radius", chassis_collision_radius, 0.0, 100.0);
  require_in_range(o, "chassis_collision_half_height", chassis_collision_half_height, 0.0, 100.0);
  require(foot_rotation.allFinite() &&
              (foot_rotation.transpose() * foot_rotation - Eigen::Matrix3d::Identity()).norm() < 1e-9 &&
              foot_rotation.determinant() > 0.0,
          std::string(o) + ".foot_rotation must be a rotation matrix");
  require_positive(o, "wheel_radius", wheel_radius);
  require_positive(o, "wheel_width", wheel_width);
  require_positive(o, "standard_height", standard_height);
  require_positive(o, "standard_foot_radius", standard_foot_radius);
  require_positive(o, "gravity", gravity);
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const JointSpec& j = joints[i];
    const std::string field = "joints[" + std::to_string(i) + "]";
    const auto f = [&](const char* name) { return field + "." + name; };
    for (int k = 0; k < 3; ++k) {
      require_finite(o, f("offset").c_str(), j.offset[k]);
      require_finite(o, f("com").c_str(), j.com[k]);
      require_in_range(o, f("inertia").c_str(), j.inertia[k], 0.0, kInf);
      require_finite(o, f("geometry.p0").c_str(), j.geometry.p0[k]);
      require_finite(o, f("geometry.p1").c_str(), j.geometry.p1[k]);
    }
    require(j.axis.allFinite() && std::abs(j.axis.norm() - 1.0) < 1e-9,
            std::string(o) + "." + f("axis") + " must be a finite unit vector");
    require_in_range(o, f("lower").c_str(), j.lower, -2.0 * kPi, 2.0 * kPi);
    require_in_range(o, f("upper").c_str(), j.upper, j.lower, j.lower + 2.0 * kPi);
    require_positive(o, f("torque_limit").c_str(), j.torque_limit);
    require_in_range(o, f("mass").c_str(), j.mass, 0.0, kInf);
    require_in_range(o, f("geometry.radius").c_str(), j.geometry.radius, 0.0, 10.0);
  }
}

// SDM-B. Sources, by value:
//  * paper (seed 003): six legs, six revolute joints each, a wheel at each foot (§2.3); hexagonal
//    chassis ("hex ring", §5.1.2); chassis height 1.75 m in the studied pose (§5.1.4); the 1.2 cm
//    sag error is "less than 0.7 percent of the length of the leg" (§5.1.4), so the leg is longer
//    than 1.71 m — ours is 1.95 m from the hip pitch axis to the wheel centre.
//  * public ATHLETE facts (first generation, JPL): about 850 kg in total; the joint sequence hip
//    yaw, hip pitch, knee pitch, knee roll, ankle pitch, ankle roll with the wheel beyond the
//    last joint, which makes the knee roll, ankle pitch and ankle roll a wrist (their axes meet at
//    the ankle). The last joint, about the foot link, steers the wheel when the link is vertical.
//  * our assumptions (no public figure we trust): hip circle radius 1.3 m and hip-yaw offset
//    0.2 m (a ≈ 2.6 m hex ring, proportioned like photographs of the vehicle); thigh and shank
//    0.85 m, ankle to wheel centre 0.25 m, wheel radius 0.35 m (0.7 m pneumatic tyre); link masses
//    (12, 22, 6, 16, 4, 20 kg: actuators at the joints, the foot link carrying the wheel and its hub
//    motor), 80 kg a leg, so the chassis is 370 kg for 850 kg in total; inertias of rods and
//    spheres of those masses; joint limits wide enough for the standard stance and its mirror
//    solutions; standard foot radius 2.0 m (wheel contacts on a circle just outside the hips,
//    ATHLETE's usual walking stance).
//  * calibrated to the paper: the hip pitch torque limit, 1650 N m, makes the most loaded joint
//    (a hip pitch next to the lifted leg) read 50 % of its limit with leg 0 raised 0.2 m in the
//    standard pose and the zero-interaction distribution, as Fig. 16(a) reports (50.28 %) — the
//    only torque figure the paper gives. The other limits (knee pitch 1400, hip yaw 800, knee roll
//    500, ankle pitch 700, ankle roll 300 N m) are our assumptions in proportion to the loads
//    those joints see while walking. Fig. 16(b) (two opposed legs lifted, 43.43 %) is then a
//    prediction of the model, not an input.
WalkerParameters sdm_b_parameters() {
  WalkerParameters p;
  p.name = "SDM-B";
  p.legs = 6;
  p.hip_radius = 1.3;
  const double a1 = 0.20, thigh = 0.85, shank = 0.85, foot = 0.25;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ(), O = Eigen::Vector3d::Zero();
  p.joints = {
      joint("hip_yaw", O, Z, -75, 75, 800, 12, X * (0.5 * a1), sphere_inertia(12, 0.15),
            capsule_x(a1, 0.12)),
      joint("hip_pitch", X * a1, Y, -60, 110, 1650, 22, X * (0.4 * thigh),
            rod_inertia(22, thigh, 0.08), capsule_x(thigh, 0.10)),
      joint("knee_pitch", X * thigh, Y, -160, 160, 1400, 6, O, sphere_inertia(6, 0.12),
            capsule_x(0.0, 0.12)),
      joint("knee_roll", O, X, -175, 175, 500, 16, X * (0.5 * shank),
            rod_inertia(16, shank, 0.07), capsule_x(shank, 0.09)),
      joint("ankle_pitch", X * shank, Y, -135, 135, 700, 4, O, sphere_inertia(4, 0.1),
            capsule_x(0.0, 0.10)),
      joint("ankle_roll", O, X, -175, 175, 300, 20, X * (0.9 * foot),
            sphere_inertia(20, 0.2), capsule_x(foot, 0.07)),
  };
  p.foot_offset = X * foot;
  p.foot_rotation = foot_axes();
  p.wheel_radius = 0.35;
  p.wheel_width = 0.25;
  p.chassis_mass = 850.0 - 6 * 80.0;
  p.chassis_com = O;
  // Hex ring of radius 1.3 m and 0.3 m depth as a thin disc (our assumption).
  p.chassis_inertia = Eigen::Vector3d(0.25, 0.25, 0.5) * p.chassis_mass * 1.3 * 1.3;
  p.chassis_collision_radius = 1.42;
  p.chassis_collision_half_height = 0.15;
  p.standard_height = 1.75;
  p.standard_foot_radius = 2.0;
  return p;
}

// T12. Paper: seven joints a leg (§2.3), standard (studied) pose 2.15 m high (§5.1.4), and
// 0.9 cm being 0.4 % of the leg (§5.1.4) gives a 2.25 m leg (ours: 1.0 + 1.0 + 0.25 m). The
// position of the seventh joint is our assumption: an ankle roll about the axis normal to the
// ankle pitch and the foot link, so the wrist (knee roll, ankle pitch, ankle roll, steer) is
// redundant. Masses (≈ 1.5× SDM-B's legs; 2 × 450 kg decks plus pallet for the chassis) and
// limits are our assumptions, scaled from SDM-B.
WalkerParameters t12_parameters() {
  WalkerParameters p = sdm_b_parameters();
  p.name = "T12";
  p.hip_radius = 2.0;
  const double a1 = 0.25, thigh = 1.0, shank = 1.0, foot = 0.25;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ(), O = Eigen::Vector3d::Zero();
  p.joints = {
      joint("hip_yaw", O, Z, -75, 75, 2500, 18, X * (0.5 * a1), sphere_inertia(18, 0.18),
            capsule_x(a1, 0.14)),
      joint("hip_pitch", X * a1, Y, -60, 110, 5000, 32, X * (0.4 * thigh),
            rod_inertia(32, thigh, 0.09), capsule_x(thigh, 0.12)),
      joint("knee_pitch", X * thigh, Y, -160, 160, 4200, 9, O, sphere_inertia(9, 0.14),
            capsule_x(0.0, 0.14)),
      joint("knee_roll", O, X, -175, 175, 1000, 24, X * (0.5 * shank),
            rod_inertia(24, shank, 0.08), capsule_x(shank, 0.10)),
      joint("ankle_pitch", X * shank, Y, -135, 135, 1800, 6, O, sphere_inertia(6, 0.12),
            capsule_x(0.0, 0.12)),
      joint("ankle_roll", O, Z, -60, 60, 1200, 5, O, sphere_inertia(5, 0.1),
            capsule_x(0.0, 0.10)),
      joint("wheel_steer", O, X, -175, 175, 500, 26, X * (0.9 * foot), sphere_inertia(26, 0.22),
            capsule_x(foot, 0.08)),
  };
  p.foot_offset = X * foot;
  p.wheel_radius = 0.4;
  p.wheel_width = 0.3;
  p.chassis_mass = 1200.0;
  p.chassis_inertia = Eigen::Vector3d(0.25, 0.25, 0.5) * p.chassis_mass * 2.0 * 2.0;
  p.chassis_collision_radius = 2.15;
  p.chassis_collision_half_height = 0.2;
  p.standard_height = 2.15;
  p.standard_foot_radius = 3.0;
  return p;
}

}  // namespace ernest::walker
