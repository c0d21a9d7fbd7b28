// Self-image removal by watershed segmentation of the depth map (seed 003 §5.2): "we use the
// watershed algorithm on the depth map to find the segments closest to the camera. We assume that
// the segment that is the right size and not connected to the ground must be the leg." Steps:
//  1. the depth map as disparity-equivalent inverse depth D = f B / z (0 where nothing is hit): on
//     a plane D is affine in the pixel coordinates, so the ground is smooth in D at every range
//     and a raised leg stands out by a jump;
//  2. the edge image |grad D| (the paper names the Laplacian; its zero crossing sits on a step,
//     where the gradient has its ridge), and markers = connected regions of small edge value
//     (the paper's local minima each starting a segment);
//  3. OpenCV's cv::watershed floods from the markers over D ("each segment adds progressively
//     higher-valued neighbours until another segment is encountered"); its watershed lines join
//     the neighbouring segment continuous in D, and the few pixels it leaves on the wrong side of a
//     depth step (pieces not continuous with the rest of their segment) join the segment they are
//     continuous with;
//  4. adjacent segments whose shared border is continuous in D merge into objects; the largest
//     object is the ground; among the objects not connected to it, the closest (largest mean D)
//     of the right size is the leg, together with the other unconnected objects touching it (a
//     leg's links can occlude one another).
// The removed mask is applied before the map is fused (depth_to_points skips it).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "ernest/perception/camera.hpp"
#include "ernest/perception/self_render.hpp"
#include "ernest/perception/stereo_matcher.hpp"

namespace ernest::perception {

struct SelfImageOptions {
  double smoothing_sigma = 1.0;   ///< Gaussian blur of D before the edge image [px] (0 = off)
  /// A pixel seeds a marker where |grad D| (Sobel, per pixel) is below this [px of disparity per
  /// px]. The ground changes by ~B / H ≈ 0.07 px per image row (H the camera height), a raised
  /// leg's silhouette by several px.
  double marker_gradient = 0.25;
  int min_marker_pixels = 20;     ///< smaller flat regions seed nothing (they are flooded)
  /// Two neighbouring pixels of different segments are continuous when their D differ by at most
  /// this [px]; two segments belong to one object when at least `min_connect_pairs` of their
  /// neighbouring pairs, and at least `connect_fraction` of them, are continuous. A rock meets the
  /// ground along its base (continuous) while its top and sides jump to the ground behind it, so
  /// the fraction must stay well below one half; a raised leg has (noise aside) no continuous pair.
  double connect_jump = 1.0;
  double connect_fraction = 0.05;
  int min_connect_pairs = 10;
  double min_area_fraction = 0.002;  ///< the leg's object covers at least this share of the image
  double max_area_fraction = 0.6;    ///< ... and at most this
  int dilate_pixels = 0;             ///< grow the removed mask by this many pixels (0 = exact)
  void validate() const;
};

struct SelfImageResult {
  MaskImage removed;     ///< 1 where the leg was found (and is not fused)
  LabelImage segments;   ///< watershed segment of each pixel (1 = no return, >= 2 segments)
  LabelImage objects;    ///< object (merged segments) of each pixel; 0 = no return
  int segment_count = 0;
  int object_count = 0;
  int ground_object = 0;     ///< object id of the ground
  int leg_object = 0;        ///< object id of the closest unconnected object; 0 = none found
  std::int64_t removed_pixels = 0;
  double leg_mean_depth = 0.0;  ///< mean z of the removed pixels [m] (0 when none)
  bool found() const { return leg_object > 0; }
};

/// Watershed self-image segmentation; keeps its OpenCV buffers between calls (one per thread).
class SelfImageSegmenter {
 public:
  explicit SelfImageSegmenter(const SelfImageOptions& options = {});
  ~SelfImageSegmenter();
  SelfImageSegmenter(SelfImageSegmenter&&) noexcept;
  SelfImageSegmenter& operator=(SelfImageSegmenter&&) noexcept;

  /// Segments a depth map (z along the optical axis [m]; +inf = no return) of `camera`'s size.
  /// Throws std::invalid_argument on an empty or wrongly sized image, NaN, or z <= 0.
  void segment(const FloatImage& depth, const StereoCameraParameters& camera, SelfImageResult& out);
  SelfImageResult segment(const FloatImage& depth, const StereoCameraParameters& camera);
  const SelfImageOptions& options() const { return options_; }

 private:
  struct Impl;
  SelfImageOptions options_;
  std::unique_ptr<Impl> impl_;
};

/// Intersection over union of two 0/1 masks of equal size (1 when both are empty).
double mask_iou(const MaskImage& a, const MaskImage& b);

/// Back-projection of a depth map (X = (u - cx) z / f, Y = (v - cy) z / f) to the left camera
/// frame, skipping pixels with removed != 0 (pass an empty mask to keep all), non-finite depth
/// and depth beyond max_depth. Throws std::invalid_argument on mismatched sizes.
PointCloud depth_to_points(const FloatImage& depth, const StereoCameraParameters& camera,
                           const MaskImage& removed, double max_depth = 20.0);

}  // namespace ernest::perception
