#include "ernest/walker/self_collision.hpp"

#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include <memory>
#include <string>

#include "ernest/common/validation.hpp"

namespace ernest::walker {

namespace {

struct Shape {
  int leg, link;
  std::shared_ptr<fcl::CollisionGeometryd> geometry;
  fcl::Transform3d pose;
};

// FCL capsules lie along their local z axis, centred at the origin.
Shape capsule_shape(const LinkCapsule& c) {
  const Eigen::Vector3d axis = c.p1 - c.p0;
  const double length = axis.norm();
  fcl::Transform3d pose = fcl::Transform3d::Identity();
  pose.translation() = 0.5 * (c.p0 + c.p1);
  if (length < 1e-9) return {c.leg, c.link, std::make_shared<fcl::Sphered>(c.radius), pose};
  pose.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axis / length).toRotationMatrix();
  return {c.leg, c.link, std::make_shared<fcl::Capsuled>(c.radius, length), pose};
}

// Separation of two shapes, 0 when they intersect.
double separation(const Shape& a, const Shape& b) {
  fcl::CollisionRequestd creq;
  fcl::CollisionResultd cres;
  if (fcl::collide(a.geometry.get(), a.pose, b.geometry.get(), b.pose, creq, cres) > 0) return 0.0;
  fcl::DistanceRequestd dreq;
  fcl::DistanceResultd dres;
  return std::max(0.0, fcl::distance(a.geometry.get(), a.pose, b.geometry.get(), b.pose, dreq, dres));
}

}  // namespace

std::vector<CollisionPair> self_collisions(const WalkerModel& model,
                                           const Eigen::Ref<const Eigen::MatrixXd>& q,
                                           double clearance) {
  model.check_configuration(q);
  require_in_range("self_collisions", "clearance", clearance, 0.0, 10.0);
  const WalkerParameters& p = model.params();
  const Shape chassis{kChassis, -1,
                      std::make_shared<fcl::Cylinderd>(p.chassis_collision_radius,
                                                       2.0 * p.chassis_collision_half_height),
                      fcl::Transform3d::Identity()};
  auto shapes = [&](int leg, const Eigen::Ref<const Eigen::VectorXd>& qk) {
    std::vector<Shape> s;
    for (const LinkCapsule& c : model.leg_capsules(leg, qk)) s.push_back(capsule_shape(c));
    return s;
  };
  // Pairs of one leg (and a leg's links with the chassis) that touch in the standard stance are
  // joined by construction (neighbouring links, the wheel round the ankle, the hip in the ring):
  // they are not checked. The legs are identical, so leg 0 decides for all.
  const std::vector<Shape> rest = shapes(0, model.standard_configuration().col(0));
  const int count = static_cast<int>(rest.size());
  std::vector<char> skip(count * (count + 1), 0);  // [a][b] for b < count, [a][count] = chassis
  for (int a = 0; a < count; ++a) {
    skip[a * (count + 1) + count] = separation(rest[a], chassis) <= 0.0;
    for (int b = 0; b < count; ++b) skip[a * (count + 1) + b] = a == b || separation(rest[a], rest[b]) <= 0.0;
  }
  std::vector<std::vector<Shape>> legs(model.legs());
  for (int k = 0; k < model.legs(); ++k) legs[k] = shapes(k, q.col(k));
  std::vector<CollisionPair> out;
  auto check = [&](const Shape& a, const Shape& b) {
    const double d = separation(a, b);
    if (d <= clearance) out.push_back({a.leg, a.link, b.leg, b.link, d});
  };
  for (int k = 0; k < model.legs(); ++k)
    for (int a = 0; a < count; ++a) {
      if (!skip[a * (count + 1) + count]) check(legs[k][a], chassis);
      for (int b = a + 1; b < count; ++b)
        if (!skip[a * (count + 1) + b]) check(legs[k][a], legs[k][b]);
      for (int j = k + 1; j < model.legs(); ++j)
        for (const Shape& b : legs[j]) check(legs[k][a], b);
    }
  return out;
}

}  // namespace ernest::walker
