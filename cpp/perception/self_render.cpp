#include "ernest/perception/self_render.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"

namespace ernest::perception {

namespace {
constexpr double kPi = 3.14159265358979323846;

// Sphere of radius r around c: entry distance of the ray, or -1 (also when o is inside).
double ray_sphere(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& c,
                  double r) {
  const Eigen::Vector3d oc = o - c;
  const double b = oc.dot(d), cc = oc.squaredNorm() - r * r;
  const double h = b * b - cc;
  if (cc <= 0.0 || h < 0.0) return -1.0;
  const double t = -b - std::sqrt(h);
  return t > 0.0 ? t : -1.0;
}
}  // namespace

double intersect_solid(const RobotSolid& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  // Closed forms: the infinite cylinder about the axis (quadratic in t, written with ba·ba factored
  // in so a zero-length axis needs no division), clipped to the segment; then the end caps
  // (spheres for a capsule, discs for a cylinder).
  const Eigen::Vector3d ba = s.p1 - s.p0, oa = o - s.p0;
  const double baba = ba.squaredNorm(), bard = ba.dot(d), baoa = ba.dot(oa);
  const double r2 = s.radius * s.radius;
  if (baba < 1e-18) return s.kind == RobotSolid::Kind::Capsule ? ray_sphere(o, d, s.p0, s.radius) : -1.0;
  // inside the solid: no hit (as the Raycaster ignores a camera inside a box)
  const double along = std::clamp(baoa / baba, 0.0, 1.0);
  const double axis_dist2 = (oa - along * ba).squaredNorm();
  if (axis_dist2 <= r2 && (s.kind == RobotSolid::Kind::Capsule || (baoa >= 0.0 && baoa <= baba)))
    return -1.0;
  const double a = baba - bard * bard;
  const double b = baba * oa.dot(d) - baoa * bard;
  const double c = baba * oa.squaredNorm() - baoa * baoa - r2 * baba;
  const double h = b * b - a * c;
  if (h < 0.0) return -1.0;  // the ray misses the infinite cylinder, hence the solid
  if (a > 1e-12 * baba) {
    const double t = (-b - std::sqrt(h)) / a;
    const double y = baoa + t * bard;
    if (t > 0.0 && y > 0.0 && y < baba) return t;  // the mantle
  }
  if (s.kind == RobotSolid::Kind::Capsule) {
    const double t0 = ray_sphere(o, d, s.p0, s.radius), t1 = ray_sphere(o, d, s.p1, s.radius);
    if (t0 < 0.0) return t1;
    if (t1 < 0.0) return t0;
    return std::min(t0, t1);
  }
  // cylinder caps: the plane of the nearer end along the ray, inside the radius
  if (std::abs(bard) < 1e-12) return -1.0;
  double best = -1.0;
  for (const double end : {0.0, baba}) {
    const double t = (end - baoa) / bard;
    if (t <= 0.0) continue;
    const Eigen::Vector3d p = oa + t * d - (end / baba) * ba;
    if (p.squaredNorm() <= r2 && (best < 0.0 || t < best)) best = t;
  }
  return best;
}

std::vector<RobotSolid> walker_solids(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
                                      const Eigen::Ref<const Eigen::MatrixXd>& q) {
  require(body.matrix().allFinite(), "walker_solids: the body pose is not finite");
  model.check_configuration(q);
  std::vector<RobotSolid> out;
  const double half_width = 0.5 * model.params().wheel_width;
  for (int k = 0; k < model.legs(); ++k) {
    for (const walker::LinkCapsule& c : model.leg_capsules(k, q.col(k))) {
      RobotSolid s;
      s.label = k + 1;
      if (c.link < 0) {
        // the wheel: a cylinder (tyre width along the axle), not leg_capsules' rounded capsule
        const Eigen::Isometry3d foot = model.foot_pose(k, q.col(k));
        const Eigen::Vector3d axle = foot.linear().col(1), centre = foot.translation();
        s.kind = RobotSolid::Kind::Cylinder;
        s.p0 = body * (centre - half_width * axle);
        s.p1 = body * (centre + half_width * axle);
      } else {
        s.p0 = body * c.p0;
        s.p1 = body * c.p1;
      }
      s.radius = c.radius;
      out.push_back(s);
    }
  }
  return out;
}

StereoCameraParameters walker_hazcam() {
  StereoCameraParameters c;
  c.mount_position = Eigen::Vector3d(0.55, 0.0, -0.15);
  c.mount_pitch = 40.0 * kPi / 180.0;
  return c;
}

Eigen::Isometry3d hazcam_pose(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
                              int leg, const StereoCameraParameters& camera) {
  model.check_leg(leg);
  require(body.matrix().allFinite(), "hazcam_pose: the body pose is not finite");
  const Eigen::Vector3d hip = model.hip_mount(leg).translation();
  const double yaw = std::atan2(hip.y(), hip.x());
  const Eigen::Matrix3d r = body.linear() * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return camera.camera_pose(body.translation(), r, 0);
}

void SelfRenderOptions::validate() const {
  require_in_range("SelfRenderOptions", "disparity_sigma", disparity_sigma, 0.0, 10.0);
  require_in_range("SelfRenderOptions", "robot_grey", robot_grey, 0.0, 255.0);
}

MaskImage SelfImageFrame::mask_of(int label) const {
  return (labels.array() == label).cast<std::uint8_t>().matrix();
}

void render_with_robot(const Raycaster& scene, const std::vector<RobotSolid>& solids,
                       const Eigen::Isometry3d& pose, const StereoCameraParameters& camera,
                       const SelfRenderOptions& options, std::uint64_t frame, SelfImageFrame& out) {
  options.validate();
  for (std::size_t i = 0; i < solids.size(); ++i) {
    const RobotSolid& s = solids[i];
    require(s.p0.allFinite() && s.p1.allFinite() && std::isfinite(s.radius) && s.radius > 0.0 &&
                s.label >= 1,
            "render_with_robot: solids[" + std::to_string(i) +
                "] needs finite ends, a radius > 0 and a label >= 1");
  }
  scene.render(pose, camera, frame, out.image, out.depth);  // validates camera and pose
  const int w = camera.width, h = camera.height;
  out.labels.resize(h, w);
  const double f = camera.focal(), cx = camera.cx(), cy = camera.cy(), fb = f * camera.baseline;
  const Eigen::Matrix3d r = pose.linear();
  const Eigen::Vector3d o = pose.translation();
  // bounding spheres, so a pixel tests a solid's closed form only when its ray comes near it
  std::vector<Eigen::Vector3d> centre(solids.size());
  std::vector<double> bound(solids.size());
  for (std::size_t i = 0; i < solids.size(); ++i) {
    centre[i] = 0.5 * (solids[i].p0 + solids[i].p1);
    bound[i] = 0.5 * (solids[i].p1 - solids[i].p0).norm() + solids[i].radius;
  }
  std::mt19937_64 rng(options.seed * 0x9E3779B97F4A7C15ULL + frame + 1);
  std::normal_distribution<double> noise(0.0, 1.0);
  const float inf = std::numeric_limits<float>::infinity();
  for (int v = 0; v < h; ++v) {
    poll_interrupt();  // Ctrl-C between rows (common/interrupt.hpp); the frame is discarded
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector3d ray_cam((u - cx) / f, (v - cy) / f, 1.0);
      const double len = ray_cam.norm();
      const Eigen::Vector3d d = r * ray_cam / len;
      float& z = out.depth(v, u);
      int label = std::isnan(z) ? -1 : 0;
      double best = label < 0 ? std::numeric_limits<double>::infinity() : z * len;
      for (std::size_t i = 0; i < solids.size(); ++i) {
        const Eigen::Vector3d oc = o - centre[i];
        const double b = oc.dot(d), c = oc.squaredNorm() - bound[i] * bound[i];
        if (c > 0.0 && (b > 0.0 || b * b < c)) continue;  // misses the bounding sphere
        const double t = intersect_solid(solids[i], o, d);
        if (t > 0.0 && t < best) {
          best = t;
          label = solids[i].label;
        }
      }
      out.labels(v, u) = label;
      if (label < 0) {
        z = inf;  // no return: infinitely far (disparity 0)
        continue;
      }
      double zz = best / len;
      if (label > 0) out.image(v, u) = static_cast<std::uint8_t>(std::lround(options.robot_grey));
      if (options.disparity_sigma > 0.0) {
        // depth from a noisy disparity, as stereo triangulation returns it
        const double disp = std::max(fb / zz + options.disparity_sigma * noise(rng), 1e-3);
        zz = fb / disp;
      }
      z = static_cast<float>(zz);
    }
  }
}

}  // namespace ernest::perception
