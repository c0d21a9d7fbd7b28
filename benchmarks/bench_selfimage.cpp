// Self-imaging benchmark (seed 003 §5.2): the watershed removal of the raised leg on
// the walker hazcam's 640 x 480 depth map, against the stereo matching that produces such a depth
// map (OpenCV StereoBM with the left-right check, our default, on the same camera's rendered pair)
// as the reference; both on one OpenCV thread, medians over the scene's five leg poses x repeats.
// Also the render (terrain + robot solids) and the IoU of every pose.
//   ./run bench selfimage
#include <cstdio>
#include <opencv2/core.hpp>
#include <vector>

#include "bench_util.hpp"
#include "ernest/perception/self_image.hpp"
#include "ernest/perception/self_scene.hpp"
#include "ernest/walker/walker_parameters.hpp"

using namespace ernest;
using namespace ernest::perception;

int main() {
  const walker::WalkerModel model(walker::sdm_b_parameters());
  const SelfImageScene scene = self_image_scene(model, 3);
  const Raycaster caster(scene.terrain, scene.rocks);
  const StereoCameraParameters camera = walker_hazcam();
  cv::setNumThreads(1);
  struct Pose {
    int leg;
    double lift, reach;
  };
  const Pose poses[] = {{0, 0.4, 0.1}, {1, 0.25, 0.0}, {3, 0.55, 0.2}, {4, 0.3, -0.15}, {5, 0.45, 0.25}};
  SelfImageSegmenter seg;
  StereoMatcher matcher;  // StereoMatcherOptions defaults: StereoBM + left-right check
  SelfImageResult result;
  std::vector<double> t_seg, t_bm, t_render;
  std::printf("CPU: %s\n\n| leg | lift [m] | reach [m] | IoU | segments | removed px |\n|---|---|---|---|---|---|\n",
              bench::cpu_model().c_str());
  for (const Pose& p : poses) {
    Eigen::MatrixXd q = scene.q;
    q.col(p.leg) = raised_leg(model, p.leg, p.lift, p.reach);
    const std::vector<RobotSolid> solids = walker_solids(model, scene.body, q);
    const Eigen::Isometry3d left = hazcam_pose(model, scene.body, p.leg, camera);
    // the right camera of the pair: one baseline along the left camera's x axis
    Eigen::Isometry3d right = left;
    right.translation() += camera.baseline * left.linear().col(0);
    SelfImageFrame f, fr;
    t_render.push_back(bench::median_us([&] { render_with_robot(caster, solids, left, camera, {}, 0, f); }, 1, 3));
    render_with_robot(caster, solids, right, camera, {}, 1, fr);
    for (int r = 0; r < 7; ++r) {
      t_seg.push_back(bench::median_us([&] { seg.segment(f.depth, camera, result); }, 1, 1));
      t_bm.push_back(bench::median_us([&] { (void)matcher.compute(f.image, fr.image); }, 1, 1));
    }
    seg.segment(f.depth, camera, result);
    std::printf("| %d | %.2f | %.2f | %.3f | %d | %ld |\n", p.leg, p.lift, p.reach,
                mask_iou(result.removed, f.mask_of(p.leg + 1)), result.segment_count,
                static_cast<long>(result.removed_pixels));
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2] / 1000.0;
  };
  const double seg_ms = median(t_seg), bm_ms = median(t_bm);
  std::printf("\n| step (640 x 480, 1 OpenCV thread) | median [ms] |\n|---|---|\n");
  std::printf("| render terrain + walker solids (depth, labels) | %.1f |\n", median(t_render));
  std::printf("| StereoBM + left-right check (reference) | %.2f |\n", bm_ms);
  std::printf("| watershed self-image segmentation | %.2f |\n", seg_ms);
  std::printf("| ratio segmentation / stereo matching | %.2f |\n", seg_ms / bm_ms);
  return 0;
}
