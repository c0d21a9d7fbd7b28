#include "ernest/sensing/elevation_sampler.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "ernest/common/validation.hpp"

namespace ernest::sensing {

GridHeightSource::GridHeightSource(Eigen::MatrixXd heights, double spacing, double origin_x,
                                   double origin_y)
    : heights_(std::move(heights)), spacing_(spacing), origin_x_(origin_x), origin_y_(origin_y) {
  require(heights_.rows() >= 2 && heights_.cols() >= 2,
          "GridHeightSource: heights must be at least 2 x 2");
  require_positive("GridHeightSource", "spacing", spacing_);
  require_finite("GridHeightSource", "origin_x", origin_x_);
  require_finite("GridHeightSource", "origin_y", origin_y_);
}

bool GridHeightSource::height(double x, double y, double& z) const {
  const double u = (x - origin_x_) / spacing_, v = (y - origin_y_) / spacing_;
  if (!(u >= 0.0 && v >= 0.0 && u <= heights_.rows() - 1 && v <= heights_.cols() - 1)) return false;
  const Eigen::Index i = std::min<Eigen::Index>(static_cast<Eigen::Index>(u), heights_.rows() - 2);
  const Eigen::Index j = std::min<Eigen::Index>(static_cast<Eigen::Index>(v), heights_.cols() - 2);
  const double fu = u - i, fv = v - j;
  const double h00 = heights_(i, j), h10 = heights_(i + 1, j), h01 = heights_(i, j + 1),
               h11 = heights_(i + 1, j + 1);
  if (!(std::isfinite(h00) && std::isfinite(h10) && std::isfinite(h01) && std::isfinite(h11))) {
    return false;
  }
  z = (1 - fu) * (1 - fv) * h00 + fu * (1 - fv) * h10 + (1 - fu) * fv * h01 + fu * fv * h11;
  return true;
}

void ElevationSamplingOptions::validate() const {
  const char* o = "ElevationSamplingOptions";
  require(wheel_xy.allFinite(), "ElevationSamplingOptions.wheel_xy must be finite");
  require_in_range(o, "ground_z", ground_z, -5.0, 5.0);
  require_in_range(o, "first_offset", first_offset, -2.0, 5.0);
  require_positive(o, "spacing", spacing);
  require_in_range(o, "points_per_wheel", points_per_wheel, 3, 3);
  require_positive(o, "search_step", search_step);
  require_in_range(o, "search_step", search_step, 1e-9, 100.0);
  try {
    require_in_range(o, "search_range", search_range, search_step, 100.0);
  } catch (const std::invalid_argument& e) {  // a coupled bound: name the other field too
    throw std::invalid_argument(std::string(e.what()) + " (the lower bound is search_step = " +
                                std::to_string(search_step) + ")");
  }
}

ElevationSampler::ElevationSampler(const ElevationSamplingOptions& options) : options_(options) {
  options_.validate();
}

Eigen::Vector2d ElevationSampler::point(int k) const {
  require_in_range("ElevationSampler.point", "k", k, 0, kElevationSamples - 1);
  const int wheel = k / options_.points_per_wheel, j = k % options_.points_per_wheel;
  return {options_.wheel_xy(wheel, 0) + options_.first_offset + j * options_.spacing,
          options_.wheel_xy(wheel, 1)};
}

bool fill_line(const Eigen::Ref<const Eigen::VectorXd>& s, Eigen::Ref<Eigen::VectorXd> values,
               const Eigen::Ref<const Eigen::Array<bool, Eigen::Dynamic, 1>>& valid) {
  const Eigen::Index n = s.size();
  require(values.size() == n && valid.size() == n, "fill_line: s, values, valid sizes differ");
  bool any = false;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (valid[i]) {
      any = true;
      continue;
    }
    Eigen::Index lo = i - 1, hi = i + 1;
    while (lo >= 0 && !valid[lo]) --lo;
    while (hi < n && !valid[hi]) ++hi;
    if (lo >= 0 && hi < n) {
      const double t = (s[i] - s[lo]) / (s[hi] - s[lo]);
      values[i] = values[lo] + t * (values[hi] - values[lo]);
    } else if (lo >= 0) {
      values[i] = values[lo];  // beyond the last valid value: hold it (no slope extrapolation)
    } else if (hi < n) {
      values[i] = values[hi];
    }
  }
  return any;
}

ElevationSample ElevationSampler::sample(const Eigen::Vector3d& position,
                                         const Eigen::Matrix3d& rotation,
                                         const HeightSource& source) const {
  require(position.allFinite() && rotation.allFinite(),
          "ElevationSampler.sample: pose must be finite");
  const ElevationSamplingOptions& o = options_;
  // Sampling direction: the chassis forward axis projected on the horizontal plane.
  Eigen::Vector2d dir = rotation.col(0).head<2>();
  const double dn = dir.norm();
  dir = dn > 1e-9 ? Eigen::Vector2d(dir / dn) : Eigen::Vector2d(1.0, 0.0);
  const int steps = static_cast<int>(std::ceil(o.search_range / o.search_step));

  ElevationSample out;
  for (int k = 0; k < kElevationSamples; ++k) {
    const Eigen::Vector2d pc = point(k);
    const Eigen::Vector3d pw = rotation * Eigen::Vector3d(pc.x(), pc.y(), o.ground_z) + position;
    double z = 0.0;
    int kind = 0;
    if (!source.height(pw.x(), pw.y(), z)) {
      // Hole: nearest valid data behind and ahead along the sampling line, then fill_line.
      Eigen::Vector3d line_s(0.0, 0.0, 0.0), line_z(0.0, 0.0, 0.0);
      Eigen::Array<bool, 3, 1> ok(false, false, false);
      for (int i = 1; i <= steps && !ok[0]; ++i) {
        const Eigen::Vector2d q = pw.head<2>() - i * o.search_step * dir;
        if (source.height(q.x(), q.y(), line_z[0])) ok[0] = true, line_s[0] = -i * o.search_step;
      }
      for (int i = 1; i <= steps && !ok[2]; ++i) {
        const Eigen::Vector2d q = pw.head<2>() + i * o.search_step * dir;
        if (source.height(q.x(), q.y(), line_z[2])) ok[2] = true, line_s[2] = i * o.search_step;
      }
      if (!ok[0]) line_s[0] = -1.0;
      if (!ok[2]) line_s[2] = 1.0;
      if (fill_line(line_s, line_z, ok)) {
        z = line_z[1];
        kind = ok[0] && ok[2] ? 1 : 2;
      } else {
        kind = 3;
      }
    }
    if (kind == 3) {
      out.values[k] = 0.0;
    } else {
      const Eigen::Vector3d q = rotation.transpose() * (Eigen::Vector3d(pw.x(), pw.y(), z) - position);
      out.values[k] = q.z() - o.ground_z;
    }
    out.source[k] = kind;
  }
  return out;
}

}  // namespace ernest::sensing
