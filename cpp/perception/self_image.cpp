#include "ernest/perception/self_image.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <unordered_map>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"

namespace ernest::perception {

void SelfImageOptions::validate() const {
  const char* o = "SelfImageOptions";
  require_in_range(o, "smoothing_sigma", smoothing_sigma, 0.0, 20.0);
  require_in_range(o, "marker_gradient", marker_gradient, 1e-6, 1e3);
  require_in_range(o, "min_marker_pixels", min_marker_pixels, 1, 1e7);
  require_in_range(o, "connect_jump", connect_jump, 1e-6, 1e3);
  require_in_range(o, "connect_fraction", connect_fraction, 0.0, 1.0);
  require_in_range(o, "min_connect_pairs", min_connect_pairs, 1, 1e7);
  require_in_range(o, "min_area_fraction", min_area_fraction, 0.0, 1.0);
  require_in_range(o, "max_area_fraction", max_area_fraction, min_area_fraction, 1.0);
  require_in_range(o, "dilate_pixels", dilate_pixels, 0, 50);
}

namespace {
int find(std::vector<int>& parent, int a) {
  while (parent[a] != a) a = parent[a] = parent[parent[a]];
  return a;
}
void unite(std::vector<int>& parent, int a, int b) {
  a = find(parent, a);
  b = find(parent, b);
  if (a != b) parent[std::max(a, b)] = std::min(a, b);
}
struct PairCount {
  std::int64_t total = 0, continuous = 0;
};
}  // namespace

struct SelfImageSegmenter::Impl {
  cv::Mat disp, smooth, gx, gy, grad, flat, components, stats, centroids, grey, rgb, markers, removed;
  std::vector<int> marker_of_component, parent, object_of_segment, object_parent;
  std::vector<std::int64_t> seg_area, obj_area, group_area;
  std::vector<double> seg_sum, obj_sum, group_sum;
  std::unordered_map<std::uint64_t, PairCount> pairs;
  std::vector<int> open, pixel_parent, piece_size, piece_label;
  std::vector<std::pair<int, int>> assign;
};

SelfImageSegmenter::SelfImageSegmenter(const SelfImageOptions& options)
    : options_(options), impl_(std::make_unique<Impl>()) {
  options_.validate();
}
SelfImageSegmenter::~SelfImageSegmenter() = default;
SelfImageSegmenter::SelfImageSegmenter(SelfImageSegmenter&&) noexcept = default;
SelfImageSegmenter& SelfImageSegmenter::operator=(SelfImageSegmenter&&) noexcept = default;

SelfImageResult SelfImageSegmenter::segment(const FloatImage& depth, const StereoCameraParameters& camera) {
  SelfImageResult r;
  segment(depth, camera, r);
  return r;
}

void SelfImageSegmenter::segment(const FloatImage& depth, const StereoCameraParameters& camera,
                                 SelfImageResult& out) {
  camera.validate();
  const int h = camera.height, w = camera.width;
  require(depth.size() > 0, "SelfImageSegmenter.segment: the depth image is empty");
  require(depth.rows() == h && depth.cols() == w,
          "SelfImageSegmenter.segment: the depth image is " + std::to_string(depth.rows()) + " x " +
              std::to_string(depth.cols()) + ", the camera's is " + std::to_string(h) + " x " +
              std::to_string(w) + " (rows x cols)");
  Impl& m = *impl_;
  const SelfImageOptions& o = options_;
  const double fb = camera.focal() * camera.baseline;
  // 1. D = f B / z; +inf (no return) -> 0
  m.disp.create(h, w, CV_32F);
  // Ctrl-C (common/interrupt.hpp) between rows, between the OpenCV passes and between the
  // flood rounds; the workspace is scratch and `out` is written last.
  for (int v = 0; v < h; ++v) {
    poll_interrupt();
    float* dr = m.disp.ptr<float>(v);
    for (int u = 0; u < w; ++u) {
      const float z = depth(v, u);
      if (!(z > 0.0f)) {  // NaN, zero, negative, -inf
        throw std::invalid_argument("SelfImageSegmenter.segment: depth(" + std::to_string(v) + ", " +
                                    std::to_string(u) + ") = " + std::to_string(z) +
                                    " is not a depth > 0 (use +inf for a pixel without a return)");
      }
      dr[u] = std::isinf(z) ? 0.0f : static_cast<float>(fb / z);
    }
  }
  // 2. edge image and markers
  if (o.smoothing_sigma > 0.0)
    cv::GaussianBlur(m.disp, m.smooth, cv::Size(0, 0), o.smoothing_sigma, o.smoothing_sigma,
                     cv::BORDER_REPLICATE);
  else
    m.disp.copyTo(m.smooth);
  cv::Sobel(m.smooth, m.gx, CV_32F, 1, 0, 3, 0.125);  // /8: per-pixel slope
  cv::Sobel(m.smooth, m.gy, CV_32F, 0, 1, 3, 0.125);
  cv::magnitude(m.gx, m.gy, m.grad);
  poll_interrupt();
  m.flat.create(h, w, CV_8U);
  for (int v = 0; v < h; ++v) {
    poll_interrupt();
    const float* g = m.grad.ptr<float>(v);
    const float* d = m.disp.ptr<float>(v);
    std::uint8_t* f = m.flat.ptr<std::uint8_t>(v);
    for (int u = 0; u < w; ++u) f[u] = (d[u] > 0.0f && g[u] < o.marker_gradient) ? 255 : 0;
  }
  const int ncomp = cv::connectedComponentsWithStats(m.flat, m.components, m.stats, m.centroids, 8, CV_32S);
  m.marker_of_component.assign(ncomp, 0);
  int labels = 1;  // 1 = no return
  for (int c = 1; c < ncomp; ++c)
    if (m.stats.at<int>(c, cv::CC_STAT_AREA) >= o.min_marker_pixels) m.marker_of_component[c] = ++labels;
  m.markers.create(h, w, CV_32S);  // continuous: indexed as v * w + u below
  for (int v = 0; v < h; ++v) {
    poll_interrupt();
    const int* cc = m.components.ptr<int>(v);
    const float* d = m.disp.ptr<float>(v);
    int* mk = m.markers.ptr<int>(v);
    for (int u = 0; u < w; ++u) mk[u] = d[u] == 0.0f ? 1 : m.marker_of_component[cc[u]];
  }
  // 3. flood over the unsmoothed D scaled to 8 bits (cv::watershed takes a colour image; grey in
  // all channels): the blur would move the segment borders off the depth steps by a pixel, and a
  // rim of leg pixels left with the ground is a false obstacle after fusion
  double dmax = 0.0;
  cv::minMaxLoc(m.disp, nullptr, &dmax);
  m.disp.convertTo(m.grey, CV_8U, dmax > 0.0 ? 255.0 / dmax : 0.0);
  cv::cvtColor(m.grey, m.rgb, cv::COLOR_GRAY2BGR);
  poll_interrupt();
  cv::watershed(m.rgb, m.markers);
  poll_interrupt();
  // Watershed lines (-1) and unreached pixels (0) join a neighbouring segment: first, in rounds,
  // those with a neighbour continuous in D (the side of the depth step they lie on), then the rest
  // to the neighbour closest in D. A round reads only the labels of the rounds before it, so the
  // scan order cannot carry a label along a line of unassigned pixels.
  m.open.clear();
  for (int v = 0; v < h; ++v) {
    poll_interrupt();
    const int* mk = m.markers.ptr<int>(v);
    for (int u = 0; u < w; ++u)
      if (mk[u] < 1) m.open.push_back(v * w + u);
  }
  int* mk = m.markers.ptr<int>(0);  // continuous (created above)
  const float* dd = m.disp.ptr<float>(0);
  for (const float limit : {static_cast<float>(o.connect_jump), std::numeric_limits<float>::infinity()}) {
    for (int round = 0; round < 10000 && !m.open.empty(); ++round) {
      poll_interrupt();
      m.assign.clear();
      for (const int i : m.open) {
        const int v = i / w, u = i % w;
        int best = 0;
        float err = limit;
        const int nb[4] = {u > 0 ? i - 1 : -1, u + 1 < w ? i + 1 : -1, v > 0 ? i - w : -1,
                           v + 1 < h ? i + w : -1};
        for (const int j : nb) {
          if (j < 0 || mk[j] < 1) continue;
          const float e = std::abs(dd[j] - dd[i]);
          if (e <= err) {
            err = e;
            best = mk[j];
          }
        }
        if (best > 0) m.assign.emplace_back(i, best);
      }
      if (m.assign.empty()) break;
      for (const auto& [i, l] : m.assign) mk[i] = l;
      m.open.erase(std::remove_if(m.open.begin(), m.open.end(), [&](int i) { return mk[i] >= 1; }),
                   m.open.end());
    }
  }
  for (const int i : m.open) mk[i] = 1;  // no segment anywhere near (no marker at all)
  // cv::watershed queues a pixel once, at the priority of the neighbour that reached it first, so
  // a few pixels just behind a depth step can end up on the wrong side of it. Repair: pieces of a
  // segment that are not continuous in D with the rest of it (components of the same-label,
  // continuous-D pixel graph smaller than a marker) and are continuous with another segment join it.
  const int n_px = h * w;
  m.pixel_parent.resize(n_px);
  std::iota(m.pixel_parent.begin(), m.pixel_parent.end(), 0);
  const float jump = static_cast<float>(o.connect_jump);
  poll_interrupt();
  for (int i = 0; i < n_px; ++i) {
    const int u = i % w;
    if (u + 1 < w && mk[i + 1] == mk[i] && std::abs(dd[i + 1] - dd[i]) <= jump) unite(m.pixel_parent, i, i + 1);
    if (i + w < n_px && mk[i + w] == mk[i] && std::abs(dd[i + w] - dd[i]) <= jump) unite(m.pixel_parent, i, i + w);
  }
  m.piece_size.assign(n_px, 0);
  for (int i = 0; i < n_px; ++i) ++m.piece_size[find(m.pixel_parent, i)];
  m.piece_label.assign(n_px, 0);
  for (int i = 0; i < n_px; ++i) {
    const int root = find(m.pixel_parent, i);
    if (m.piece_size[root] >= o.min_marker_pixels || m.piece_label[root] != 0 || mk[i] == 1) continue;
    const int u = i % w, v = i / w;
    const int nb[4] = {u > 0 ? i - 1 : -1, u + 1 < w ? i + 1 : -1, v > 0 ? i - w : -1, v + 1 < h ? i + w : -1};
    for (const int j : nb)
      if (j >= 0 && mk[j] != mk[i] && mk[j] > 1 && std::abs(dd[j] - dd[i]) <= jump) {
        m.piece_label[root] = mk[j];
        break;
      }
  }
  for (int i = 0; i < n_px; ++i) {
    const int l = m.piece_label[find(m.pixel_parent, i)];
    if (l != 0) mk[i] = l;
  }
  // 4. segment statistics and the continuity of every shared border
  m.seg_area.assign(labels + 1, 0);
  m.seg_sum.assign(labels + 1, 0.0);
  m.pairs.clear();
  auto pair_at = [&](int a, int b, float da, float db) {
    if (a == b || a < 2 || b < 2) return;
    const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
    PairCount& p = m.pairs[key];
    ++p.total;
    if (std::abs(da - db) <= o.connect_jump) ++p.continuous;
  };
  for (int v = 0; v < h; ++v) {
    poll_interrupt();
    const int* mk = m.markers.ptr<int>(v);
    const float* d = m.disp.ptr<float>(v);
    for (int u = 0; u < w; ++u) {
      const int l = std::max(mk[u], 1);
      ++m.seg_area[l];
      m.seg_sum[l] += d[u];
      if (u + 1 < w) pair_at(l, mk[u + 1], d[u], d[u + 1]);
      if (v + 1 < h) pair_at(l, m.markers.at<int>(v + 1, u), d[u], m.disp.at<float>(v + 1, u));
    }
  }
  m.parent.resize(labels + 1);
  std::iota(m.parent.begin(), m.parent.end(), 0);
  for (const auto& [key, p] : m.pairs)
    if (p.continuous >= o.min_connect_pairs && p.continuous >= o.connect_fraction * p.total)
      unite(m.parent, static_cast<int>(key >> 32), static_cast<int>(key & 0xffffffffu));
  // objects 1..n (segment 1, no return, is object 0)
  m.object_of_segment.assign(labels + 1, 0);
  int objects = 0;
  for (int s = 2; s <= labels; ++s)
    if (find(m.parent, s) == s) m.object_of_segment[s] = ++objects;
  for (int s = 2; s <= labels; ++s) m.object_of_segment[s] = m.object_of_segment[find(m.parent, s)];
  m.obj_area.assign(objects + 1, 0);
  m.obj_sum.assign(objects + 1, 0.0);
  for (int s = 2; s <= labels; ++s) {
    m.obj_area[m.object_of_segment[s]] += m.seg_area[s];
    m.obj_sum[m.object_of_segment[s]] += m.seg_sum[s];
  }
  int ground = 0;
  for (int k = 1; k <= objects; ++k)
    if (ground == 0 || m.obj_area[k] > m.obj_area[ground]) ground = k;
  // groups of touching objects other than the ground (a leg's links in front of one another)
  m.object_parent.resize(objects + 1);
  std::iota(m.object_parent.begin(), m.object_parent.end(), 0);
  for (const auto& [key, p] : m.pairs) {
    const int a = m.object_of_segment[key >> 32], b = m.object_of_segment[key & 0xffffffffu];
    if (a != ground && b != ground) unite(m.object_parent, a, b);
  }
  m.group_area.assign(objects + 1, 0);
  m.group_sum.assign(objects + 1, 0.0);
  for (int k = 1; k <= objects; ++k) {
    if (k == ground) continue;
    const int g = find(m.object_parent, k);
    m.group_area[g] += m.obj_area[k];
    m.group_sum[g] += m.obj_sum[k];
  }
  const double n = static_cast<double>(h) * w;
  int leg_group = 0;
  double leg_mean = -1.0;
  for (int g = 1; g <= objects; ++g) {
    if (g == ground || find(m.object_parent, g) != g || m.group_area[g] == 0) continue;
    const double area = static_cast<double>(m.group_area[g]);
    if (area < o.min_area_fraction * n || area > o.max_area_fraction * n) continue;  // wrong size
    const double mean = m.group_sum[g] / area;
    if (mean > leg_mean) {
      leg_mean = mean;
      leg_group = g;
    }
  }
  // 5. outputs
  out.segments.resize(h, w);
  out.objects.resize(h, w);
  out.removed.resize(h, w);
  m.removed.create(h, w, CV_8U);
  int leg_object = 0;
  double best_mean = -1.0;
  for (int k = 1; k <= objects; ++k) {
    if (leg_group == 0 || k == ground || find(m.object_parent, k) != leg_group) continue;
    const double mean = m.obj_sum[k] / std::max<std::int64_t>(m.obj_area[k], 1);
    if (mean > best_mean) {
      best_mean = mean;
      leg_object = k;
    }
  }
  for (int v = 0; v < h; ++v) {
    poll_interrupt();
    const int* mk = m.markers.ptr<int>(v);
    std::uint8_t* rm = m.removed.ptr<std::uint8_t>(v);
    for (int u = 0; u < w; ++u) {
      const int s = std::max(mk[u], 1), k = m.object_of_segment[s];
      out.segments(v, u) = s;
      out.objects(v, u) = k;
      rm[u] = (leg_group > 0 && k > 0 && k != ground && find(m.object_parent, k) == leg_group) ? 1 : 0;
    }
  }
  if (o.dilate_pixels > 0 && leg_group > 0)
    cv::dilate(m.removed, m.removed, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(3, 3)),
               cv::Point(-1, -1), o.dilate_pixels);
  out.removed_pixels = 0;
  double zsum = 0.0;
  for (int v = 0; v < h; ++v) {
    poll_interrupt();
    const std::uint8_t* rm = m.removed.ptr<std::uint8_t>(v);
    for (int u = 0; u < w; ++u) {
      out.removed(v, u) = rm[u];
      if (rm[u] && std::isfinite(depth(v, u))) {
        ++out.removed_pixels;
        zsum += depth(v, u);
      }
    }
  }
  out.segment_count = labels - 1;
  out.object_count = objects;
  out.ground_object = ground;
  out.leg_object = leg_object;
  out.leg_mean_depth = out.removed_pixels > 0 ? zsum / static_cast<double>(out.removed_pixels) : 0.0;
}

double mask_iou(const MaskImage& a, const MaskImage& b) {
  require(a.rows() == b.rows() && a.cols() == b.cols(), "mask_iou: the masks differ in size");
  std::int64_t inter = 0, uni = 0;
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    const bool x = a.data()[i] != 0, y = b.data()[i] != 0;
    inter += x && y;
    uni += x || y;
  }
  return uni == 0 ? 1.0 : static_cast<double>(inter) / static_cast<double>(uni);
}

PointCloud depth_to_points(const FloatImage& depth, const StereoCameraParameters& camera,
                           const MaskImage& removed, double max_depth) {
  camera.validate();
  require_positive("depth_to_points", "max_depth", max_depth);
  require(depth.rows() == camera.height && depth.cols() == camera.width,
          "depth_to_points: the depth image is " + std::to_string(depth.rows()) + " x " +
              std::to_string(depth.cols()) + ", the camera's is " + std::to_string(camera.height) +
              " x " + std::to_string(camera.width));
  require(removed.size() == 0 || (removed.rows() == depth.rows() && removed.cols() == depth.cols()),
          "depth_to_points: the removed mask differs in size from the depth image");
  const double f = camera.focal(), cx = camera.cx(), cy = camera.cy();
  std::int64_t n = 0;
  auto keep = [&](int v, int u) {
    const float z = depth(v, u);
    return std::isfinite(z) && z > 0.0f && z <= max_depth && (removed.size() == 0 || removed(v, u) == 0);
  };
  for (int v = 0; v < depth.rows(); ++v)
    for (int u = 0; u < depth.cols(); ++u) n += keep(v, u);
  PointCloud c;
  c.points.resize(n, 3);
  c.pixels.resize(n, 2);
  Eigen::Index i = 0;
  for (int v = 0; v < depth.rows(); ++v)
    for (int u = 0; u < depth.cols(); ++u) {
      if (!keep(v, u)) continue;
      const double z = depth(v, u);
      c.points.row(i) << (u - cx) * z / f, (v - cy) * z / f, z;
      c.pixels.row(i) << u, v;
      ++i;
    }
  return c;
}

}  // namespace ernest::perception
