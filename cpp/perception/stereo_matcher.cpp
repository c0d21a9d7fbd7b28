#include "ernest/perception/stereo_matcher.hpp"

#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <cstdlib>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"

namespace ernest::perception {

void StereoMatcherOptions::validate() const {
  const char* o = "StereoMatcherOptions";
  require_in_range(o, "num_disparities", num_disparities, 16, 1024);
  require(num_disparities % 16 == 0, "StereoMatcherOptions.num_disparities = " +
                                         std::to_string(num_disparities) +
                                         " must be a multiple of 16");
  require_in_range(o, "block_size", block_size, 3, 255);
  require(block_size % 2 == 1, "StereoMatcherOptions.block_size = " + std::to_string(block_size) +
                                   " must be odd");
  if (algorithm == StereoAlgorithm::BlockMatching) {
    require_in_range(o, "block_size", block_size, 5, 255);  // StereoBM's own lower limit
  }
  require_in_range(o, "uniqueness_ratio", uniqueness_ratio, 0, 100);
  require_in_range(o, "texture_threshold", texture_threshold, 0, 10000);
  require_in_range(o, "speckle_window", speckle_window, 0, 10000);
  require_in_range(o, "speckle_range", speckle_range, 0, 1000);
  require_in_range(o, "pre_filter_cap", pre_filter_cap, 1, 63);
  if (max_lr_difference) require_in_range(o, "max_lr_difference", *max_lr_difference, 0, 1024);
}

struct StereoMatcher::Impl {
  cv::Ptr<cv::StereoMatcher> matcher;
};

StereoMatcher::StereoMatcher(const StereoMatcherOptions& options)
    : options_(options), impl_(std::make_unique<Impl>()) {
  options_.validate();
  const auto& o = options_;
  if (o.algorithm == StereoAlgorithm::BlockMatching) {
    auto bm = cv::StereoBM::create(o.num_disparities, o.block_size);
    bm->setUniquenessRatio(o.uniqueness_ratio);
    bm->setTextureThreshold(o.texture_threshold);
    bm->setSpeckleWindowSize(o.speckle_window);
    bm->setSpeckleRange(o.speckle_range);
    bm->setPreFilterCap(o.pre_filter_cap);
    // StereoBM does not apply disp12MaxDiff itself (measured, OpenCV 4.6): compute() checks the
    // left-right consistency with a second match of the mirrored pair.
    impl_->matcher = bm;
  } else {
    // P1, P2: OpenCV's documented choice 8 and 32 x channels x block area
    const int area = o.block_size * o.block_size;
    impl_->matcher = cv::StereoSGBM::create(0, o.num_disparities, o.block_size, 8 * area, 32 * area,
                                            o.max_lr_difference.value_or(-1),  // OpenCV's "off"
                                            o.pre_filter_cap, o.uniqueness_ratio,
                                            o.speckle_window, o.speckle_range,
                                            cv::StereoSGBM::MODE_SGBM);
  }
}

StereoMatcher::~StereoMatcher() = default;
StereoMatcher::StereoMatcher(StereoMatcher&&) noexcept = default;
StereoMatcher& StereoMatcher::operator=(StereoMatcher&&) noexcept = default;

FloatImage StereoMatcher::compute(const GrayImage& left, const GrayImage& right) const {
  require(left.size() > 0 && right.size() > 0, "StereoMatcher.compute: empty image");
  require(left.rows() == right.rows() && left.cols() == right.cols(),
          "StereoMatcher.compute: left is " + std::to_string(left.cols()) + "x" +
              std::to_string(left.rows()) + " but right is " + std::to_string(right.cols()) + "x" +
              std::to_string(right.rows()));
  require(left.cols() > options_.num_disparities + options_.block_size,
          "StereoMatcher.compute: image narrower than num_disparities + block_size");
  const int h = static_cast<int>(left.rows()), w = static_cast<int>(left.cols());
  // OpenCV views of the row-major Eigen buffers (no copy)
  const cv::Mat l(h, w, CV_8UC1, const_cast<std::uint8_t*>(left.data()));
  const cv::Mat r(h, w, CV_8UC1, const_cast<std::uint8_t*>(right.data()));
  cv::Mat disp16;
  // Ctrl-C (common/interrupt.hpp) before and between the OpenCV passes and between output rows:
  // a pass itself is one OpenCV call (its time grows with width x height x num_disparities).
  poll_interrupt();
  impl_->matcher->compute(l, r, disp16);
  // Right-image disparity for the left-right check: match the mirrored pair with the roles
  // swapped (a right pixel u_R = u_L - d is, mirrored, the left pixel of a pair with disparity d).
  const bool lr_check =
      options_.algorithm == StereoAlgorithm::BlockMatching && options_.max_lr_difference.has_value();
  cv::Mat right16;
  if (lr_check) {
    cv::Mat lf, rf, d;
    cv::flip(l, lf, 1);
    cv::flip(r, rf, 1);
    poll_interrupt();
    impl_->matcher->compute(rf, lf, d);
    cv::flip(d, right16, 1);
  }
  FloatImage out(h, w);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const int min_valid = 16 * impl_->matcher->getMinDisparity();  // invalid = (min - 1) * 16
  const int tol16 = 16 * options_.max_lr_difference.value_or(0);
  for (int v = 0; v < h; ++v) {
    poll_interrupt();
    const auto* row = disp16.ptr<std::int16_t>(v);
    const auto* rrow = lr_check ? right16.ptr<std::int16_t>(v) : nullptr;
    for (int u = 0; u < w; ++u) {
      bool ok = row[u] >= min_valid;
      if (ok && lr_check) {
        const int ur = u - (row[u] + 8) / 16;
        ok = ur >= 0 && rrow[ur] >= min_valid && std::abs(rrow[ur] - row[u]) <= tol16;
      }
      out(v, u) = ok ? row[u] / 16.0f : nan;
    }
  }
  return out;
}

void set_opencv_threads(int threads) {
  require_in_range("set_opencv_threads", "threads", threads, 0, 1024);
  cv::setNumThreads(threads);
}

int opencv_threads() { return cv::getNumThreads(); }

PointCloud disparity_to_points(const FloatImage& disparity, const StereoCameraParameters& camera,
                               double min_disparity, double max_depth) {
  camera.validate();
  require(disparity.rows() == camera.height && disparity.cols() == camera.width,
          "disparity_to_points: disparity is " + std::to_string(disparity.cols()) + "x" +
              std::to_string(disparity.rows()) + " but the camera is " +
              std::to_string(camera.width) + "x" + std::to_string(camera.height));
  require_positive("disparity_to_points", "min_disparity", min_disparity);
  require_positive("disparity_to_points", "max_depth", max_depth);
  const double f = camera.focal(), cx = camera.cx(), cy = camera.cy(), fb = f * camera.baseline;
  Eigen::Index n = 0;
  for (Eigen::Index k = 0; k < disparity.size(); ++k) {
    const double d = disparity.data()[k];
    if (std::isfinite(d) && d > min_disparity && fb / d <= max_depth) ++n;
  }
  PointCloud cloud;
  cloud.points.resize(n, 3);
  cloud.pixels.resize(n, 2);
  Eigen::Index i = 0;
  for (int v = 0; v < disparity.rows(); ++v) {
    for (int u = 0; u < disparity.cols(); ++u) {
      const double d = disparity(v, u);
      if (!(std::isfinite(d) && d > min_disparity && fb / d <= max_depth)) continue;
      const double z = fb / d;
      cloud.points.row(i) << (u - cx) * z / f, (v - cy) * z / f, z;
      cloud.pixels.row(i) << u, v;
      ++i;
    }
  }
  return cloud;
}

}  // namespace ernest::perception
