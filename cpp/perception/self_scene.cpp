#include "ernest/perception/self_scene.hpp"

#include <cmath>
#include <random>
#include <string>

#include "ernest/common/validation.hpp"
#include "ernest/walker/leg_ik.hpp"

namespace ernest::perception {

SelfImageScene self_image_scene(const walker::WalkerModel& model, std::uint64_t seed, int rocks) {
  // leg k's hip lies at 2 pi k / legs about the body axis (WalkerParameters)
  require_in_range("self_image_scene", "rocks", rocks, 0, 100);
  SelfImageScene s;
  const double spacing = 0.05, half = 8.0;
  const int n = static_cast<int>(std::lround(2.0 * half / spacing)) + 1;
  Eigen::MatrixXd h(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double x = -half + i * spacing, y = -half + j * spacing;
      h(i, j) = 0.03 * std::sin(1.3 * x + 0.2) * std::cos(0.9 * y);
    }
  s.terrain = dynamics::HeightMap(h, spacing, -half, -half);
  std::mt19937_64 rng(seed);
  // rocks spread over the legs' directions (rock k in front of leg k mod legs, within ±0.4 rad),
  // so every hazcam sees some
  std::uniform_real_distribution<double> angle(-0.4, 0.4), radius(2.9, 3.8),
      size(0.15, 0.35), yaw(0.0, 1.5);
  for (int k = 0; k < rocks; ++k) {
    dynamics::BoxObstacle b;
    const double a = 2.0 * 3.14159265358979 * (k % model.legs()) / model.legs() + angle(rng);
    const double r = radius(rng);
    b.size = Eigen::Vector3d(size(rng), size(rng), size(rng));
    const double x = r * std::cos(a), y = r * std::sin(a);
    b.centre = Eigen::Vector3d(x, y, s.terrain.height(x, y) + 0.4 * b.size.z());  // partly buried
    b.yaw = yaw(rng);
    s.rocks.push_back(b);
  }
  s.body = model.standard_body_pose();
  s.q = model.standard_configuration();
  return s;
}

Eigen::VectorXd raised_leg(const walker::WalkerModel& model, int leg, double lift, double reach) {
  model.check_leg(leg);
  require_in_range("raised_leg", "lift", lift, 0.0, 2.0);
  require_in_range("raised_leg", "reach", reach, -1.0, 1.0);
  const Eigen::VectorXd q0 = model.standard_configuration().col(leg);
  Eigen::Isometry3d target = model.foot_pose(leg, q0);
  const Eigen::Vector3d hip = model.hip_mount(leg).translation();
  const Eigen::Vector3d out = Eigen::Vector3d(hip.x(), hip.y(), 0.0).normalized();
  target.translation() += reach * out + lift * Eigen::Vector3d::UnitZ();
  walker::LegIk ik(model);
  Eigen::VectorXd q(q0.size());
  require(ik.solve_from(leg, target, q0, q),
          "raised_leg: no joint angles lift leg " + std::to_string(leg) + " by " +
              std::to_string(lift) + " m at reach " + std::to_string(reach) + " m");
  return q;
}

}  // namespace ernest::perception
