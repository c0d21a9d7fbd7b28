// Perception benchmark: one 640x480 stereo pair of the rock-field scenario at the start
// pose: ray casting one camera, StereoBM on the pair (OpenCV on one thread, and with its default
// threads), back-projection, and fusing the frame's cloud into the 10 m x 10 m, 1 cm map (target
// <= 10 ms on one core). Medians of repeats. The Python half (bench_perception.py) measures the
// same StereoBM call through cv2 and a numpy implementation of the same map update.
//   ./run bench perception
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <opencv2/core.hpp>
#include <vector>

#include "ernest/envs/scenarios.hpp"
#include "ernest/perception/stereo_mapper.hpp"

using namespace ernest;
using namespace ernest::perception;
using Clock = std::chrono::steady_clock;

namespace {
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
template <class F>
double median_ms(int repeats, F&& f) {
  std::vector<double> t;
  for (int k = 0; k < repeats; ++k) {
    const auto a = Clock::now();
    f();
    t.push_back(std::chrono::duration<double, std::milli>(Clock::now() - a).count());
  }
  return median(t);
}
}  // namespace

int main() {
  envs::ScenarioOptions so;
  so.kind = envs::ScenarioKind::RockField;
  const envs::Scenario sc = envs::generate_scenario(so, 0);
  StereoMapperOptions mo;
  StereoMapper mapper(sc.terrain, sc.obstacles, mo);
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd(sc.start_heading, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d pos(sc.start_x, sc.start_y, sc.terrain.height(sc.start_x, sc.start_y) + 0.17);
  const StereoFrame& fr = mapper.capture(pos, rot);
  std::printf("rock field seed 0: %zu rocks, %ld points in the frame\n", sc.obstacles.size(),
              static_cast<long>(fr.cloud.size()));

  GrayImage img;
  FloatImage depth;
  const double render = median_ms(5, [&] { mapper.raycaster().render(fr.left_pose, mo.camera, 0, img, depth); });
  const int default_threads = cv::getNumThreads();
  StereoMatcherOptions plain = mo.matcher;
  plain.max_lr_difference.reset();
  StereoMatcher bm(plain), bm_lr(mo.matcher);
  const double bm_default = median_ms(21, [&] { bm.compute(fr.left, fr.right); });
  cv::setNumThreads(1);
  const double bm_one = median_ms(21, [&] { bm.compute(fr.left, fr.right); });
  const double bm_lr_one = median_ms(21, [&] { bm_lr.compute(fr.left, fr.right); });
  StereoMatcherOptions sg = mo.matcher;
  sg.algorithm = StereoAlgorithm::SemiGlobal;
  sg.block_size = 5;
  StereoMatcher sgbm(sg);
  const double sgbm_one = median_ms(5, [&] { sgbm.compute(fr.left, fr.right); });
  const FloatImage disparity = bm_lr.compute(fr.left, fr.right);
  PointCloud cloud;
  const double backproject = median_ms(21, [&] { cloud = disparity_to_points(disparity, mo.camera, 0.5, mo.max_depth); });
  ElevationMap map(mo.map);
  map.move_to(pos.x(), pos.y());
  map.fuse_cloud(cloud.points, fr.left_pose, mo.camera);  // first touch of the pages
  const double fuse = median_ms(21, [&] { map.fuse_cloud(cloud.points, fr.left_pose, mo.camera); });

  std::printf("\n| step (640x480, one core unless noted) | median [ms] |\n|---|---|\n");
  std::printf("| ray cast one camera | %.1f |\n", render);
  std::printf("| StereoBM, OpenCV default threads (%d) | %.2f |\n", default_threads, bm_default);
  std::printf("| StereoBM, 1 thread | %.2f |\n", bm_one);
  std::printf("| StereoBM + left-right check (default), 1 thread | %.2f |\n", bm_lr_one);
  std::printf("| StereoSGBM (option), 1 thread | %.2f |\n", sgbm_one);
  std::printf("| disparity -> %ld points | %.2f |\n", static_cast<long>(cloud.size()), backproject);
  std::printf("| fuse the cloud into the 1000x1000 map | %.2f (target <= 10) |\n", fuse);
  return 0;
}
