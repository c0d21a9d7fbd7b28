// Self-imaging (seed 003 §4.3, Fig. 8): the walker's hazard cameras look through the robot and see
// its legs, so a depth map of the terrain also holds the raised leg. This renders that depth map:
// the terrain (and rocks) through the Raycaster, and the walker's links as capsules and its wheels
// as capped cylinders, ray-cast together (nearest hit wins); a label image records which leg each
// pixel sees, the ground truth the segmentation (self_image.hpp) is scored against.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "ernest/perception/camera.hpp"
#include "ernest/perception/raycaster.hpp"
#include "ernest/walker/walker_model.hpp"

namespace ernest::perception {

using LabelImage = Eigen::Matrix<std::int32_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using MaskImage = Eigen::Matrix<std::uint8_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// A simple solid of the robot in the world frame: a capsule (segment p0–p1 swept by a sphere) or
/// a capped cylinder (axis p0–p1). `label` >= 1 is written to the label image where it is seen.
struct RobotSolid {
  enum class Kind { Capsule, Cylinder };
  Kind kind = Kind::Capsule;
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
  Eigen::Vector3d p1 = Eigen::Vector3d::Zero();
  double radius = 0.0;
  int label = 1;
};

/// Ray o + t d (d unit) against one solid: the entry distance t > 0, or a negative value when the
/// ray misses it (or starts inside it).
double intersect_solid(const RobotSolid& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d);

/// The walker's solids in the world for a body pose (body -> world) and joint angles q (joints x
/// legs): every link's collision capsule, and each wheel as a cylinder of wheel_radius and
/// wheel_width along its axle; label = leg + 1.
std::vector<RobotSolid> walker_solids(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
                                      const Eigen::Ref<const Eigen::MatrixXd>& q);

/// A walker hazard camera pair (ours: the paper gives no placement; §5.2.1 only says the T12
/// cameras were placed to see the legs while walking): under the chassis, 0.55 m out from the
/// body centre towards a leg's hip, 0.15 m below the hip plane, tilted 40° down, 640 x 480.
StereoCameraParameters walker_hazcam();
/// Pose (camera -> world) of the left camera of the hazcam pair facing `leg` (the camera's mount is
/// rotated about the body z axis onto the leg's hip direction).
Eigen::Isometry3d hazcam_pose(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
                              int leg, const StereoCameraParameters& camera);

struct SelfRenderOptions {
  /// Stereo-like depth noise: each pixel's disparity f B / z gets Gaussian noise of this sigma
  /// [px] (0 = exact depth). 0.3 px is what StereoBM reaches on the simulated images
  /// (ElevationMapOptions::disparity_sigma).
  double disparity_sigma = 0.3;
  double robot_grey = 90.0;  ///< grey level of the robot in the image (untextured paint)
  std::uint64_t seed = 0;    ///< noise seed
  void validate() const;
};

/// Depth (z along the optical axis [m], +inf where nothing is hit), grey image, and labels
/// (0 terrain or rock, s.label where solid s is the nearest hit, -1 nothing hit) of one camera.
struct SelfImageFrame {
  GrayImage image;
  FloatImage depth;
  LabelImage labels;
  /// labels == label as a 0/1 mask (the ground truth of one leg).
  MaskImage mask_of(int label) const;
};

/// Renders the terrain of `scene` and the solids together (the nearest surface along each ray).
/// `frame` selects the noise draws. Resizes the outputs.
void render_with_robot(const Raycaster& scene, const std::vector<RobotSolid>& solids,
                       const Eigen::Isometry3d& pose, const StereoCameraParameters& camera,
                       const SelfRenderOptions& options, std::uint64_t frame, SelfImageFrame& out);

}  // namespace ernest::perception
