#include "ernest/perception/raycaster.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"

namespace ernest::perception {

namespace {

std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Value in [-1, 1] at an integer lattice point.
double lattice(std::int64_t x, std::int64_t y, std::int64_t z, std::uint64_t seed) {
  // one mixing round over a linear combination with large odd constants (distinct per axis)
  const std::uint64_t h = splitmix(seed ^ (static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ULL) ^
                                   (static_cast<std::uint64_t>(y) * 0xC2B2AE3D27D4EB4FULL) ^
                                   (static_cast<std::uint64_t>(z) * 0x165667B19E3779F9ULL));
  return static_cast<double>(h >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

// Trilinear value noise with a smoothstep fade (continuous, so the texture never swims).
double value_noise(double x, double y, double z, std::uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy),
             iz = static_cast<std::int64_t>(fz);
  auto fade = [](double t) { return t * t * (3.0 - 2.0 * t); };
  const double u = fade(x - fx), v = fade(y - fy), w = fade(z - fz);
  double c[2][2];
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b) {
      const double l0 = lattice(ix, iy + a, iz + b, seed), l1 = lattice(ix + 1, iy + a, iz + b, seed);
      c[a][b] = l0 + u * (l1 - l0);
    }
  }
  const double c0 = c[0][0] + v * (c[1][0] - c[0][0]), c1 = c[0][1] + v * (c[1][1] - c[0][1]);
  return c0 + w * (c1 - c0);
}

}  // namespace

void RenderOptions::validate() const {
  const char* o = "RenderOptions";
  require_in_range(o, "texture_wavelength", texture_wavelength, 1e-3, 100.0);
  require_in_range(o, "texture_octaves", texture_octaves, 1, 12);
  require_in_range(o, "texture_gain", texture_gain, 0.0, 1.0);
  require_in_range(o, "albedo", albedo, 0.0, 1.0);
  require_in_range(o, "contrast", contrast, 0.0, 1.0);
  require_in_range(o, "ambient", ambient, 0.0, 1.0);
  require_in_range(o, "sun_elevation", sun_elevation, 0.0, 1.5707963267948966);
  require_in_range(o, "sun_azimuth", sun_azimuth, -10.0, 10.0);
  require_in_range(o, "noise_sigma", noise_sigma, 0.0, 50.0);
  require_in_range(o, "sky", sky, 0.0, 255.0);
  require_in_range(o, "max_range", max_range, 0.1, 1000.0);
}

Raycaster::Raycaster(const dynamics::HeightMap& terrain,
                     const std::vector<dynamics::BoxObstacle>& boxes, const RenderOptions& options)
    : terrain_(terrain), options_(options) {
  options_.validate();
  require(terrain_.heights().allFinite(), "Raycaster: the height map holds non-finite heights");
  // Bound on the bilinear surface's gradient: within a cell |dh/dx| <= max |x difference| / s.
  const Eigen::MatrixXd& h = terrain_.heights();
  double mx = 0.0, my = 0.0;
  if (h.rows() > 1) mx = (h.bottomRows(h.rows() - 1) - h.topRows(h.rows() - 1)).cwiseAbs().maxCoeff();
  if (h.cols() > 1) my = (h.rightCols(h.cols() - 1) - h.leftCols(h.cols() - 1)).cwiseAbs().maxCoeff();
  lipschitz_ = std::hypot(mx, my) / terrain_.spacing();
  top_ = h.maxCoeff() + 1.0;
  for (const auto& b : boxes) {
    b.validate();
    Box q;
    q.rt = (Eigen::AngleAxisd(b.yaw, Eigen::Vector3d::UnitZ()) *
            Eigen::AngleAxisd(b.pitch, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(b.roll, Eigen::Vector3d::UnitX()))
               .toRotationMatrix()
               .transpose();  // same Z-Y-X convention as envs::box_rotation
    q.centre = b.centre;
    q.half = 0.5 * b.size;
    q.radius = q.half.norm();
    top_ = std::max(top_, b.centre.z() + q.radius + 1.0);
    all_boxes_.push_back(static_cast<int>(boxes_.size()));
    boxes_.push_back(q);
  }
  sun_ = Eigen::Vector3d(std::cos(options_.sun_elevation) * std::cos(options_.sun_azimuth),
                         std::cos(options_.sun_elevation) * std::sin(options_.sun_azimuth),
                         std::sin(options_.sun_elevation));
}

bool Raycaster::intersect_terrain(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                  double t_max, double& t) const {
  auto gap = [&](double s) {
    return o.z() + s * d.z() - terrain_.height(o.x() + s * d.x(), o.y() + s * d.y());
  };
  double tc = 0.0, g = gap(0.0);
  if (g <= 0.0) {
    t = 0.0;
    return true;
  }
  // Lipschitz marching: the gap closes at most at rate L |d_xy| - d_z per unit t, so a step of
  // g / rate never passes the surface; below min_step we step anyway and bisect a sign change.
  const double rate = lipschitz_ * std::hypot(d.x(), d.y()) - d.z();
  if (rate <= 0.0) return false;
  const double min_step = 0.25 * terrain_.spacing();
  while (tc < t_max) {
    const double tn = std::min(tc + std::max(g / rate, min_step), t_max);
    const double gn = gap(tn);
    if (gn < 1e-6) {  // within a micrometre, or crossed: refine by Illinois regula falsi
      double lo = tc, hi = tn, glo = g, ghi = gn;
      int side = 0;
      for (int k = 0; k < 30 && ghi < -1e-7; ++k) {
        const double mid = hi - ghi * (hi - lo) / (ghi - glo);
        const double gm = gap(mid);
        if (gm > 0.0) {
          lo = mid;
          glo = gm;
          if (side == -1) ghi *= 0.5;
          side = -1;
        } else {
          hi = mid;
          ghi = gm;
          if (side == 1) glo *= 0.5;
          side = 1;
        }
        if (gm >= 0.0 && gm < 1e-6) {
          hi = mid;
          break;
        }
      }
      t = hi;
      return true;
    }
    tc = tn;
    g = gn;
  }
  return false;
}

bool Raycaster::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& t,
                          Eigen::Vector3d& normal) const {
  return intersect_boxes(o, d, t, normal, all_boxes_.data(), static_cast<int>(all_boxes_.size()));
}

bool Raycaster::intersect_boxes(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& t,
                                Eigen::Vector3d& normal, const int* candidates, int count) const {
  double best = options_.max_range;
  bool hit = false;
  for (int c_i = 0; c_i < count; ++c_i) {
    const Box& b = boxes_[candidates[c_i]];
    const Eigen::Vector3d oc = o - b.centre;
    const double along = oc.dot(d), c = oc.squaredNorm() - b.radius * b.radius;
    if (c > 0.0 && (along > 0.0 || along * along < c)) continue;  // misses the bounding sphere
    const Eigen::Vector3d q0 = b.rt * oc, qd = b.rt * d;
    double lo = -std::numeric_limits<double>::infinity(), hi = -lo;
    int face = -1;
    bool ok = true;
    for (int k = 0; k < 3 && ok; ++k) {
      if (std::abs(qd[k]) < 1e-12) {
        ok = std::abs(q0[k]) <= b.half[k];
        continue;
      }
      double t1 = (-b.half[k] - q0[k]) / qd[k], t2 = (b.half[k] - q0[k]) / qd[k];
      if (t1 > t2) std::swap(t1, t2);
      if (t1 > lo) {
        lo = t1;
        face = k;
      }
      hi = std::min(hi, t2);
      ok = lo <= hi;
    }
    if (!ok || face < 0 || lo <= 0.0 || lo >= best) continue;  // camera inside a box: ignored
    best = lo;
    hit = true;
    Eigen::Vector3d nb = Eigen::Vector3d::Zero();
    nb[face] = qd[face] > 0.0 ? -1.0 : 1.0;
    normal = b.rt.transpose() * nb;
  }
  double tt;
  if (intersect_terrain(o, d, best, tt)) {
    const Eigen::Vector3d p = o + tt * d;
    terrain_.height_normal(p.x(), p.y(), normal);
    best = tt;
    hit = true;
  }
  t = best;
  return hit;
}

double Raycaster::surface_height(double x, double y) const {
  const Eigen::Vector3d o(x, y, top_);
  double t;
  Eigen::Vector3d n;
  // the height map continues flat beyond its border, so a vertical ray always hits (max_range
  // permitting: fall back to the terrain if the drop is longer)
  if (!intersect(o, -Eigen::Vector3d::UnitZ(), t, n)) return terrain_.height(x, y);
  return top_ - t;
}

double Raycaster::texture(const Eigen::Vector3d& p, double footprint) const {
  double sum = 0.0, norm = 0.0, amp = 1.0, lambda = options_.texture_wavelength;
  for (int k = 0; k < options_.texture_octaves; ++k) {
    // fully present when the wavelength spans >= 4 pixels, gone at the 2-pixel Nyquist limit
    const double w = std::clamp(lambda / (2.0 * footprint) - 1.0, 0.0, 1.0);
    if (w > 0.0) {
      const std::uint64_t s = splitmix(options_.seed + 0x1234567ULL * (k + 1));
      sum += w * amp * value_noise(p.x() / lambda, p.y() / lambda, p.z() / lambda, s);
    }
    norm += amp;
    amp *= options_.texture_gain;
    lambda *= 0.5;
  }
  return 2.5 * sum / norm;  // trilinear value noise has a std of ~0.3: bring it to ~[-1, 1]
}

void Raycaster::render(const Eigen::Isometry3d& pose, const StereoCameraParameters& camera,
                       std::uint64_t frame, GrayImage& image, FloatImage& depth) const {
  camera.validate();
  require(pose.matrix().allFinite(), "Raycaster.render: the camera pose is not finite");
  const int w = camera.width, h = camera.height;
  image.resize(h, w);
  depth.resize(h, w);
  const double f = camera.focal(), cx = camera.cx(), cy = camera.cy();
  const Eigen::Matrix3d r = pose.linear();
  const Eigen::Vector3d o = pose.translation();
  std::mt19937_64 rng(splitmix(options_.seed ^ splitmix(frame + 0x51ED)));
  std::normal_distribution<double> noise(0.0, 1.0);
  // Box culling per 16 x 16 pixel tile: a box can only be hit inside the image rectangle that
  // bounds the projection of its bounding sphere (conservative: corners of x/z and y/z over the
  // sphere's box); a sphere reaching behind the image plane goes into every tile.
  constexpr int kTile = 16;
  const int tw = (w + kTile - 1) / kTile, th = (h + kTile - 1) / kTile;
  std::vector<std::vector<int>> tiles(static_cast<std::size_t>(tw) * th);
  const Eigen::Matrix3d rt = r.transpose();
  for (std::size_t i = 0; i < boxes_.size(); ++i) {
    const Eigen::Vector3d c = rt * (boxes_[i].centre - o);
    const double rad = boxes_[i].radius;
    if (c.z() + rad <= 0.0 || c.norm() - rad > options_.max_range) continue;  // behind or too far
    int u0 = 0, u1 = tw - 1, v0 = 0, v1 = th - 1;
    if (c.z() - rad > 1e-3) {
      auto lo_hi = [&](double a, double& lo, double& hi) {
        const double q[4] = {(a - rad) / (c.z() - rad), (a - rad) / (c.z() + rad),
                             (a + rad) / (c.z() - rad), (a + rad) / (c.z() + rad)};
        lo = *std::min_element(q, q + 4);
        hi = *std::max_element(q, q + 4);
      };
      double xl, xh, yl, yh;
      lo_hi(c.x(), xl, xh);
      lo_hi(c.y(), yl, yh);
      const double ul = cx + f * xl, uh = cx + f * xh, vl = cy + f * yl, vh = cy + f * yh;
      if (uh < -1.0 || ul > w || vh < -1.0 || vl > h) continue;  // off the image
      u0 = std::clamp(static_cast<int>(std::floor(ul)) / kTile, 0, tw - 1);
      u1 = std::clamp(static_cast<int>(std::ceil(uh)) / kTile, 0, tw - 1);
      v0 = std::clamp(static_cast<int>(std::floor(vl)) / kTile, 0, th - 1);
      v1 = std::clamp(static_cast<int>(std::ceil(vh)) / kTile, 0, th - 1);
    }
    for (int tv = v0; tv <= v1; ++tv)
      for (int tu = u0; tu <= u1; ++tu) tiles[static_cast<std::size_t>(tv) * tw + tu].push_back(static_cast<int>(i));
  }
  for (int v = 0; v < h; ++v) {
    poll_interrupt();  // Ctrl-C between rows (common/interrupt.hpp); the raycaster is unchanged
    for (int u = 0; u < w; ++u) {
      const std::vector<int>& cand = tiles[static_cast<std::size_t>(v / kTile) * tw + u / kTile];
      const Eigen::Vector3d ray_cam((u - cx) / f, (v - cy) / f, 1.0);
      const double len = ray_cam.norm();
      const Eigen::Vector3d d = r * ray_cam / len;
      double t;
      Eigen::Vector3d n;
      double value = options_.sky;
      if (intersect_boxes(o, d, t, n, cand.data(), static_cast<int>(cand.size()))) {
        depth(v, u) = static_cast<float>(t / len);  // z along the optical axis
        const Eigen::Vector3d p = o + t * d;
        const double cosine = std::max(std::abs(n.dot(d)), 0.1);
        const double albedo =
            std::clamp(options_.albedo * (1.0 + options_.contrast * texture(p, t / (f * cosine))),
                       0.0, 1.0);
        const double light = options_.ambient + (1.0 - options_.ambient) * std::max(0.0, n.dot(sun_));
        value = 255.0 * albedo * light;
      } else {
        depth(v, u) = std::numeric_limits<float>::quiet_NaN();
      }
      if (options_.noise_sigma > 0.0) value += options_.noise_sigma * noise(rng);
      image(v, u) = static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L));
    }
  }
}

}  // namespace ernest::perception
