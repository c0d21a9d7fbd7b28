// Tests of the self-imaging pipeline (seed 003 §4.3, §5.2): the robot solids' ray intersections
// against closed forms, the rendered leg mask, the watershed removal scored by intersection over
// union against the rendered mask on several legs and poses, the elevation map with and without
// the removal (the leg must show as a false obstacle without it and vanish with it), and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "test_util.hpp"
#include "ernest/perception/elevation_map.hpp"
#include "ernest/perception/self_image.hpp"
#include "ernest/perception/self_scene.hpp"
#include "ernest/walker/walker_parameters.hpp"

using namespace ernest;
using namespace ernest::perception;
using ernest::testing::invalid_argument_message;

namespace {

struct Fixture {
  walker::WalkerModel model{walker::sdm_b_parameters()};
  SelfImageScene scene = self_image_scene(model, 3);
  Raycaster caster{scene.terrain, scene.rocks};
  StereoCameraParameters camera = walker_hazcam();

  // Renders the walker with `leg` raised (lift, reach) from that leg's hazcam.
  SelfImageFrame render(int leg, double lift, double reach, Eigen::Isometry3d* pose_out = nullptr,
                        double sigma = 0.3) const {
    Eigen::MatrixXd q = scene.q;
    q.col(leg) = raised_leg(model, leg, lift, reach);
    const Eigen::Isometry3d pose = hazcam_pose(model, scene.body, leg, camera);
    SelfRenderOptions ro;
    ro.disparity_sigma = sigma;
    SelfImageFrame f;
    render_with_robot(caster, walker_solids(model, scene.body, q), pose, camera, ro,
                      static_cast<std::uint64_t>(leg), f);
    if (pose_out) *pose_out = pose;
    return f;
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

}  // namespace

TEST(SelfImageSolids, CapsuleAndCylinderMatchClosedForms) {
  const Eigen::Vector3d o(0, 0, 0), d(1, 0, 0);
  RobotSolid cap{RobotSolid::Kind::Capsule, {5, -1, 0}, {5, 1, 0}, 0.5, 1};
  EXPECT_NEAR(intersect_solid(cap, o, d), 4.5, 1e-12);  // the mantle, across the axis
  RobotSolid along{RobotSolid::Kind::Capsule, {3, 0, 0}, {6, 0, 0}, 0.5, 1};
  EXPECT_NEAR(intersect_solid(along, o, d), 2.5, 1e-12);  // the end sphere, down the axis
  RobotSolid cyl = along;
  cyl.kind = RobotSolid::Kind::Cylinder;
  EXPECT_NEAR(intersect_solid(cyl, o, d), 3.0, 1e-12);  // the end disc
  // a ray passing 0.4 above the axis of a crossing cylinder: t = 5 - sqrt(0.5^2 - 0.4^2) = 4.7
  RobotSolid wheel{RobotSolid::Kind::Cylinder, {5, -0.1, 0}, {5, 0.1, 0}, 0.5, 1};
  const Eigen::Vector3d slanted = Eigen::Vector3d(1, 0, 0);
  EXPECT_NEAR(intersect_solid(wheel, Eigen::Vector3d(0, 0, 0.4), slanted), 5.0 - 0.3, 1e-12);
  EXPECT_LT(intersect_solid(wheel, Eigen::Vector3d(0, 0, 0.6), slanted), 0.0);  // above it
  EXPECT_LT(intersect_solid(wheel, Eigen::Vector3d(0, 0.2, 0), slanted), 0.0);  // beside it
  EXPECT_LT(intersect_solid(cap, Eigen::Vector3d(5, 0, 0), d), 0.0);            // from inside
}

TEST(SelfImageRender, RaisedLegIsSeenInFrontOfTheTerrain) {
  const Fixture& fx = fixture();
  Eigen::Isometry3d pose;
  const SelfImageFrame f = fx.render(0, 0.4, 0.1, &pose, 0.0);
  const MaskImage leg = f.mask_of(1);
  const double share = leg.cast<double>().mean();
  EXPECT_GT(share, 0.02);
  EXPECT_LT(share, 0.5);
  // every leg pixel is nearer than the terrain (with rocks) along the same ray
  const double fo = fx.camera.focal();
  int checked = 0;
  for (int v = 0; v < f.depth.rows(); v += 7)
    for (int u = 0; u < f.depth.cols(); u += 7) {
      if (!leg(v, u)) continue;
      const Eigen::Vector3d ray((u - fx.camera.cx()) / fo, (v - fx.camera.cy()) / fo, 1.0);
      double t;
      Eigen::Vector3d n;
      ASSERT_TRUE(fx.caster.intersect(pose.translation(), (pose.linear() * ray).normalized(), t, n));
      EXPECT_LT(f.depth(v, u), t / ray.norm() - 0.05);
      ++checked;
    }
  EXPECT_GT(checked, 20);
}

TEST(SelfImageSegmentation, RemovedSegmentMatchesTheRenderedLeg) {
  const Fixture& fx = fixture();
  SelfImageSegmenter seg;
  struct Pose {
    int leg;
    double lift, reach;
  };
  // different legs, lifts from a low mid-step to a high one, in and out
  for (const Pose p : {Pose{0, 0.4, 0.1}, Pose{1, 0.25, 0.0}, Pose{3, 0.55, 0.2}, Pose{4, 0.3, -0.15},
                       Pose{5, 0.45, 0.25}}) {
    const SelfImageFrame f = fx.render(p.leg, p.lift, p.reach);
    const SelfImageResult r = seg.segment(f.depth, fx.camera);
    ASSERT_TRUE(r.found()) << "leg " << p.leg;
    const double iou = mask_iou(r.removed, f.mask_of(p.leg + 1));
    std::printf("leg %d lift %.2f reach %.2f: IoU %.4f, %d segments, %d objects\n", p.leg, p.lift,
                p.reach, iou, r.segment_count, r.object_count);
    EXPECT_GE(iou, 0.9) << "leg " << p.leg << " lift " << p.lift << " reach " << p.reach;
    EXPECT_GT(r.segment_count, 1);
    EXPECT_NE(r.leg_object, r.ground_object);
  }
}

TEST(SelfImageSegmentation, NoFalseObstacleLeftWhereTheLegWas) {
  const Fixture& fx = fixture();
  Eigen::Isometry3d pose;
  const SelfImageFrame f = fx.render(0, 0.4, 0.1, &pose);
  const SelfImageResult r = SelfImageSegmenter().segment(f.depth, fx.camera);
  ElevationMapOptions mo;
  mo.length = 8.0;
  mo.resolution = 0.02;
  ElevationMap with_leg(mo), removed(mo);
  with_leg.move_to(fx.scene.body.translation().x(), fx.scene.body.translation().y());
  removed.move_to(fx.scene.body.translation().x(), fx.scene.body.translation().y());
  with_leg.fuse_cloud(depth_to_points(f.depth, fx.camera, MaskImage(), 6.0).points, pose, fx.camera);
  removed.fuse_cloud(depth_to_points(f.depth, fx.camera, r.removed, 6.0).points, pose, fx.camera);
  // Cells under the leg's image: those holding a point of a rendered leg pixel.
  // Tolerance 5 cm: the stereo-like noise (0.3 px) gives ~1-2 cm per cell at these ranges.
  constexpr double kTolerance = 0.05;
  const MaskImage not_leg = (f.labels.array() != 1).cast<std::uint8_t>().matrix();
  const PointCloud leg_points = depth_to_points(f.depth, fx.camera, not_leg, 6.0);
  const Eigen::MatrixXd hw = with_leg.heights(), hr = removed.heights();
  Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> under = decltype(under)::Zero(hw.rows(), hw.cols());
  for (Eigen::Index k = 0; k < leg_points.size(); ++k) {
    const Eigen::Vector3d p = pose * Eigen::Vector3d(leg_points.points.row(k).transpose());
    const long i = std::lround((p.x() - with_leg.origin_x()) / mo.resolution);
    const long j = std::lround((p.y() - with_leg.origin_y()) / mo.resolution);
    if (i >= 0 && j >= 0 && i < hw.rows() && j < hw.cols()) under(i, j) = true;
  }
  int leg_cells = 0, known_after = 0, false_after = 0;
  double worst_before = 0.0, worst_after = 0.0;
  for (int i = 0; i < hw.rows(); ++i)
    for (int j = 0; j < hw.cols(); ++j) {
      if (!under(i, j)) continue;
      const double x = with_leg.origin_x() + i * mo.resolution, y = with_leg.origin_y() + j * mo.resolution;
      const double truth = fx.caster.surface_height(x, y);
      ++leg_cells;
      ASSERT_FALSE(std::isnan(hw(i, j)));
      worst_before = std::max(worst_before, hw(i, j) - truth);
      if (std::isnan(hr(i, j))) continue;
      ++known_after;
      worst_after = std::max(worst_after, std::abs(hr(i, j) - truth));
      if (std::abs(hr(i, j) - truth) > kTolerance) {
        ++false_after;
        std::printf("false obstacle at (%.2f, %.2f): %.3f m\n", x, y, hr(i, j) - truth);
      }
    }
  EXPECT_GT(leg_cells, 200);        // the leg is in the map without removal ...
  EXPECT_GT(worst_before, 0.3);     // ... as an obstacle tens of cm high
  EXPECT_EQ(false_after, 0) << "worst " << worst_after << " over " << known_after << " cells";
  EXPECT_GT(known_after, 0);        // some of those cells now hold the ground seen under the leg
  std::printf("%d cells under the leg: worst %.3f m above the surface without removal; %d known "
              "with it, worst |error| %.3f m\n", leg_cells, worst_before, known_after, worst_after);
}

TEST(SelfImageSegmentation, RocksAreConnectedToTheGroundAndStay) {
  // the rocks alone from every pose's camera: each meets the ground along its base, so nothing is
  // removed (the criterion that keeps a rock next to a wheel in the map, §4.3's complaint about
  // flattening)
  const Fixture& fx = fixture();
  SelfImageSegmenter seg;
  for (const int leg : {0, 2, 4}) {
    SelfImageFrame f;
    render_with_robot(fx.caster, {}, hazcam_pose(fx.model, fx.scene.body, leg, fx.camera), fx.camera,
                      {}, 9, f);
    const SelfImageResult r = seg.segment(f.depth, fx.camera);
    EXPECT_FALSE(r.found()) << "leg " << leg << ": removed " << r.removed_pixels << " pixels";
  }
}

TEST(SelfImageInput, BadInputIsAClearError) {
  const Fixture& fx = fixture();
  SelfImageSegmenter seg;
  EXPECT_NE(invalid_argument_message([&] { seg.segment(FloatImage(), fx.camera); }).find("empty"),
            std::string::npos);
  FloatImage small = FloatImage::Constant(10, 12, 3.0f);
  EXPECT_NE(invalid_argument_message([&] { seg.segment(small, fx.camera); }).find("camera's is 480 x 640"),
            std::string::npos);
  FloatImage d = FloatImage::Constant(fx.camera.height, fx.camera.width, 3.0f);
  d(5, 7) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(invalid_argument_message([&] { seg.segment(d, fx.camera); }).find("depth(5, 7)"),
            std::string::npos);
  d(5, 7) = -1.0f;
  EXPECT_NE(invalid_argument_message([&] { seg.segment(d, fx.camera); }).find("depth > 0"),
            std::string::npos);
  d(5, 7) = std::numeric_limits<float>::infinity();  // no return: allowed
  EXPECT_NO_THROW(seg.segment(d, fx.camera));
  SelfImageOptions o;
  o.connect_fraction = 1.5;
  EXPECT_NE(invalid_argument_message([&] { o.validate(); }).find("SelfImageOptions.connect_fraction = 1.5"),
            std::string::npos);
  o = {};
  o.max_area_fraction = 0.001;  // below min_area_fraction
  EXPECT_THROW(SelfImageSegmenter{o}, std::invalid_argument);
  EXPECT_THROW(depth_to_points(d, fx.camera, MaskImage::Zero(3, 3)), std::invalid_argument);
  EXPECT_THROW(mask_iou(MaskImage::Zero(3, 3), MaskImage::Zero(3, 4)), std::invalid_argument);
  RobotSolid bad;
  bad.radius = std::numeric_limits<double>::quiet_NaN();
  SelfImageFrame f;
  EXPECT_THROW(render_with_robot(fx.caster, {bad}, Eigen::Isometry3d::Identity(), fx.camera, {}, 0, f),
               std::invalid_argument);
  EXPECT_THROW(raised_leg(fx.model, 0, std::nan(""), 0.0), std::invalid_argument);
}
