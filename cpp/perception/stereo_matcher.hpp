// Stereo matching (seed 004 §2.4: "dense 3D point clouds are generated using the OpenCV stereo
// block-matching (StereoBM) implementation [33]"): OpenCV StereoBM, or StereoSGBM as an option, on
// a rectified pair -> disparity [px] -> points in the left camera frame.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>

#include "ernest/perception/camera.hpp"
#include "ernest/perception/raycaster.hpp"

namespace ernest::perception {

enum class StereoAlgorithm { BlockMatching, SemiGlobal };

struct StereoMatcherOptions {
  StereoAlgorithm algorithm = StereoAlgorithm::BlockMatching;  ///< StereoBM (the paper's)
  int num_disparities = 64;   ///< search range [px], a multiple of 16 (64: depth >= ~0.78 m)
  int block_size = 15;        ///< odd matching window [px] (OpenCV's StereoBM default)
  int uniqueness_ratio = 10;  ///< [%] margin of the best match over the second
  int texture_threshold = 10; ///< StereoBM: minimum window texture (rejects blank sky)
  int speckle_window = 100;   ///< speckle filter region [px] (0 = off)
  int speckle_range = 2;      ///< disparity spread inside a speckle region [px]
  int pre_filter_cap = 31;
  /// Left-right consistency: the largest disagreement [px] allowed between the left and the
  /// right disparity (OpenCV's disp12MaxDiff), [0, 1024]; unset: no check. Removes most of the
  /// matches that straddle an occlusion boundary, whose points would float behind rocks.
  std::optional<int> max_lr_difference = 1;
  void validate() const;
};

/// Points of a disparity image in the left camera frame (x right, y down, z forward) [m],
/// one row per valid pixel, and the pixel each came from.
struct PointCloud {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> points;
  Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> pixels;  ///< (u, v)
  Eigen::Index size() const { return points.rows(); }
};

class StereoMatcher {
 public:
  explicit StereoMatcher(const StereoMatcherOptions& options = {});
  ~StereoMatcher();
  StereoMatcher(StereoMatcher&&) noexcept;
  StereoMatcher& operator=(StereoMatcher&&) noexcept;

  /// Disparity of the left image [px] (OpenCV's 1/16-pixel fixed point divided by 16); NaN where
  /// the matcher found none. Throws std::invalid_argument on empty or differently sized images.
  FloatImage compute(const GrayImage& left, const GrayImage& right) const;
  const StereoMatcherOptions& options() const { return options_; }

 private:
  struct Impl;
  StereoMatcherOptions options_;
  std::unique_ptr<Impl> impl_;
};

/// Threads OpenCV may use for matching (cv::setNumThreads; 0 = sequential, as 1). Process-wide.
void set_opencv_threads(int threads);
/// Threads OpenCV currently uses (cv::getNumThreads).
int opencv_threads();

/// Back-projection of a rectified disparity (Z = f B / d, X = (u - cx) Z / f, Y = (v - cy) Z / f):
/// the point cloud of the valid (finite, > min_disparity) pixels with depth <= max_depth.
/// Throws std::invalid_argument if the disparity size differs from the camera's.
PointCloud disparity_to_points(const FloatImage& disparity, const StereoCameraParameters& camera,
                               double min_disparity = 0.5, double max_depth = 20.0);

}  // namespace ernest::perception
