#include "ernest/perception/elevation_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"

namespace ernest::perception {

namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInfF = std::numeric_limits<float>::infinity();
}  // namespace

void ElevationMapOptions::validate() const {
  const char* o = "ElevationMapOptions";
  require_in_range(o, "length", length, 0.1, 100.0);
  require_in_range(o, "resolution", resolution, 1e-3, 1.0);
  require_in_range(o, "length / resolution", length / resolution, 2.0, 4096.0);
  require_in_range(o, "disparity_sigma", disparity_sigma, 1e-3, 10.0);
  require_in_range(o, "pose_variance", pose_variance, 0.0, 1.0);
  require_in_range(o, "mahalanobis_threshold", mahalanobis_threshold, 0.5, 100.0);
  require_in_range(o, "multi_height_noise", multi_height_noise, 0.0, 1.0);
  require_in_range(o, "min_variance", min_variance, 1e-12, 1e-2);
}

ElevationMap::ElevationMap(const ElevationMapOptions& options) : options_(options) {
  options_.validate();
  n_ = static_cast<int>(std::lround(options_.length / options_.resolution));
  const std::size_t cells = static_cast<std::size_t>(n_) * n_;
  height_.assign(cells, kNaN);
  variance_.assign(cells, kInfF);
  acc_h_.assign(cells, 0.0f);
  acc_v_.assign(cells, 0.0f);
  acc_n_.assign(cells, 0);
  move_to(0.0, 0.0);
}

void ElevationMap::clear() {
  std::fill(height_.begin(), height_.end(), kNaN);
  std::fill(variance_.begin(), variance_.end(), kInfF);
}

void ElevationMap::clear_row(std::int64_t gi) {
  const std::int64_t r = ((gi % n_) + n_) % n_;
  std::fill_n(height_.begin() + r * n_, n_, kNaN);
  std::fill_n(variance_.begin() + r * n_, n_, kInfF);
}

void ElevationMap::clear_col(std::int64_t gj) {
  const std::int64_t c = ((gj % n_) + n_) % n_;
  for (int r = 0; r < n_; ++r) {
    height_[r * n_ + c] = kNaN;
    variance_[r * n_ + c] = kInfF;
  }
}

void ElevationMap::move_to(double x, double y) {
  // Cell indices are int64 counts of cells from the world origin: beyond 1e8 m (five times the
  // circumference of Mars) they would lose cells to rounding and then overflow.
  require_in_range("ElevationMap.move_to", "x", x, -1e8, 1e8);
  require_in_range("ElevationMap.move_to", "y", y, -1e8, 1e8);
  const double res = options_.resolution;
  const auto gi0 = static_cast<std::int64_t>(std::floor(x / res)) - n_ / 2;
  const auto gj0 = static_cast<std::int64_t>(std::floor(y / res)) - n_ / 2;
  if (placed_) {
    // Cells of the old window that are not in the new one share their slots with the cells that
    // enter: clear them.
    const std::int64_t di = gi0 - gi0_, dj = gj0 - gj0_;
    if (std::abs(di) >= n_ || std::abs(dj) >= n_) {
      clear();
    } else {
      for (std::int64_t k = 0; k < std::abs(di); ++k) clear_row(di > 0 ? gi0_ + k : gi0_ + n_ - 1 - k);
      for (std::int64_t k = 0; k < std::abs(dj); ++k) clear_col(dj > 0 ? gj0_ + k : gj0_ + n_ - 1 - k);
    }
  }
  gi0_ = gi0;
  gj0_ = gj0;
  ring_i_ = ((gi0 % n_) + n_) % n_;
  ring_j_ = ((gj0 % n_) + n_) % n_;
  placed_ = true;
}

double ElevationMap::measurement_variance(const Eigen::Vector3d& p_cam,
                                          const Eigen::Matrix3d& camera_rotation,
                                          const StereoCameraParameters& camera) const {
  // Triangulation: Z = f B / d, so sigma_Z = Z^2 / (f B) sigma_d; the point moves along its ray,
  // d p / d Z = p / Z, whose world-vertical component maps sigma_Z to the height ([17] eq. for
  // the measurement variance: J_S Sigma_S J_S^T, keeping the z row).
  camera.validate();
  require(p_cam.allFinite() && camera_rotation.allFinite(),
          "ElevationMap.measurement_variance: p_cam and camera_rotation must be finite");
  const double z = p_cam.z();
  // fuse_cloud skips such points (behind_camera): a point on or behind the image plane has no
  // disparity
  require(z > 0.0, "ElevationMap.measurement_variance: p_cam.z = " + std::to_string(z) +
                       " must be > 0 (a point in front of the camera)");
  const double sigma_z = z * z / (camera.focal() * camera.baseline) * options_.disparity_sigma;
  const double jz = camera_rotation.row(2).dot(p_cam) / z;
  const double variance = jz * jz * sigma_z * sigma_z + options_.pose_variance;
  require(std::isfinite(variance),  // a point at 1e-300 m or 1e308 m: overflow
          "ElevationMap.measurement_variance: p_cam = (" + std::to_string(p_cam.x()) + ", " +
              std::to_string(p_cam.y()) + ", " + std::to_string(p_cam.z()) +
              ") gives a variance that is not finite");
  return variance;
}

FuseStats ElevationMap::fuse_cloud(const Eigen::Ref<const Points>& points,
                                   const Eigen::Isometry3d& camera_pose,
                                   const StereoCameraParameters& camera) {
  camera.validate();
  require(camera_pose.matrix().allFinite(), "ElevationMap.fuse_cloud: camera pose is not finite");
  FuseStats stats;
  if (points.rows() == 0) {
    ++skipped_empty_;
    return stats;
  }
  const Eigen::Matrix3d r = camera_pose.linear();
  const Eigen::Vector3d t = camera_pose.translation();
  if (world_.rows() < points.rows()) {
    world_.resize(points.rows(), 3);
    point_var_.resize(points.rows());
  }
  // measurement_variance() inlined with its constants hoisted (this loop runs per pixel)
  const double k = options_.disparity_sigma / (camera.focal() * camera.baseline);
  const Eigen::RowVector3d rz = r.row(2);
  Eigen::Index m = 0;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    if (i % 4096 == 0) poll_interrupt();  // Ctrl-C before any cell changes (common/interrupt.hpp)
    const Eigen::Vector3d p = points.row(i).transpose();
    if (!p.allFinite()) {
      ++stats.non_finite;
      continue;
    }
    if (!(p.z() > 0.0)) {
      ++stats.behind_camera;
      continue;
    }
    world_.row(m) = (r * p + t).transpose();
    const double jz_sigma = rz.dot(p) * p.z() * k;  // (e_z . R p / Z) * Z^2 k
    point_var_[m] = jz_sigma * jz_sigma + options_.pose_variance;
    ++m;
  }
  const FuseStats inner = fuse_points(world_.topRows(m), point_var_.head(m));
  stats.fused_points = inner.fused_points;
  stats.non_finite += inner.non_finite;
  stats.outside_map = inner.outside_map;
  stats.new_cells = inner.new_cells;
  stats.updated_cells = inner.updated_cells;
  stats.gated_cells = inner.gated_cells;
  return stats;
}

FuseStats ElevationMap::fuse_points(const Eigen::Ref<const Points>& points,
                                    const Eigen::Ref<const Eigen::VectorXd>& variances) {
  require(points.rows() == variances.size(),
          "ElevationMap.fuse_points: " + std::to_string(points.rows()) + " points but " +
              std::to_string(variances.size()) + " variances");
  FuseStats stats;
  if (points.rows() == 0) {
    ++skipped_empty_;
    return stats;
  }
  const double inv_res = 1.0 / options_.resolution;
  touched_.clear();
  for (Eigen::Index k = 0; k < points.rows(); ++k) {
    const double x = points(k, 0), y = points(k, 1), z = points(k, 2), v = variances[k];
    if (!(std::isfinite(x) && std::isfinite(y) && std::isfinite(z) && std::isfinite(v) && v >= 0.0)) {
      ++stats.non_finite;
      continue;
    }
    const double fi = std::floor(x * inv_res), fj = std::floor(y * inv_res);
    if (!(fi >= gi0_ && fi < gi0_ + n_ && fj >= gj0_ && fj < gj0_ + n_)) {
      ++stats.outside_map;
      continue;
    }
    // storage index without a division: the window offset wrapped once past the ring start
    std::int64_t si = static_cast<std::int64_t>(fi) - gi0_ + ring_i_, sj = static_cast<std::int64_t>(fj) - gj0_ + ring_j_;
    if (si >= n_) si -= n_;
    if (sj >= n_) sj -= n_;
    const std::int64_t s = si * n_ + sj;
    if (acc_n_[s] == 0) touched_.push_back(s);
    acc_h_[s] += static_cast<float>(z);
    acc_v_[s] += static_cast<float>(v);
    ++acc_n_[s];
    ++stats.fused_points;
  }
  const double thr2 = options_.mahalanobis_threshold * options_.mahalanobis_threshold;
  for (const std::int64_t s : touched_) {
    const double n = acc_n_[s];
    const double meas = acc_h_[s] / n;
    const double mvar = std::max(acc_v_[s] / n, options_.min_variance);
    acc_h_[s] = acc_v_[s] = 0.0f;
    acc_n_[s] = 0;
    const double h = height_[s], var = variance_[s];
    if (!std::isfinite(h)) {
      height_[s] = static_cast<float>(meas);
      variance_[s] = static_cast<float>(mvar);
      ++stats.new_cells;
      continue;
    }
    const double innovation = meas - h, sum = var + mvar;
    if (innovation * innovation > thr2 * sum) {
      // the disagreement is evidence that the cell's variance is too small by about innovation^2
      // (matching artefacts at rock edges, or two surfaces in one cell): grow it by that much, so
      // the cell stays consistent and the next measurement is fused with an honest weight
      variance_[s] = static_cast<float>(var + std::max(options_.multi_height_noise, innovation * innovation));
      ++stats.gated_cells;
      continue;
    }
    // [17]: h+ = (s_p h + s_h p) / (s_h + s_p), s+ = s_h s_p / (s_h + s_p)
    height_[s] = static_cast<float>(h + var / sum * innovation);
    variance_[s] = static_cast<float>(std::max(var * mvar / sum, options_.min_variance));
    ++stats.updated_cells;
  }
  return stats;
}

bool ElevationMap::cell(double x, double y, double& z, double& variance) const {
  z = std::numeric_limits<double>::quiet_NaN();
  variance = std::numeric_limits<double>::infinity();
  if (!(std::isfinite(x) && std::isfinite(y))) return false;
  const double fi = std::floor(x / options_.resolution), fj = std::floor(y / options_.resolution);
  if (!(fi >= gi0_ && fi < gi0_ + n_ && fj >= gj0_ && fj < gj0_ + n_)) return false;
  const std::int64_t s = slot(static_cast<std::int64_t>(fi), static_cast<std::int64_t>(fj));
  if (!std::isfinite(height_[s])) return false;
  z = height_[s];
  variance = variance_[s];
  return true;
}

bool ElevationMap::height(double x, double y, double& z) const {
  double v;
  double h;
  if (!cell(x, y, h, v)) return false;
  z = h;
  return true;
}

Eigen::MatrixXd ElevationMap::heights() const {
  Eigen::MatrixXd out(n_, n_);
  for (int i = 0; i < n_; ++i)
    for (int j = 0; j < n_; ++j) out(i, j) = height_[slot(gi0_ + i, gj0_ + j)];
  return out;
}

Eigen::MatrixXd ElevationMap::variances() const {
  Eigen::MatrixXd out(n_, n_);
  for (int i = 0; i < n_; ++i)
    for (int j = 0; j < n_; ++j) out(i, j) = variance_[slot(gi0_ + i, gj0_ + j)];
  return out;
}

double ElevationMap::origin_x() const { return (static_cast<double>(gi0_) + 0.5) * options_.resolution; }
double ElevationMap::origin_y() const { return (static_cast<double>(gj0_) + 0.5) * options_.resolution; }

bool ElevationMap::consistent() const {
  for (std::size_t s = 0; s < height_.size(); ++s) {
    const bool hole = std::isnan(height_[s]) && std::isinf(variance_[s]) && variance_[s] > 0;
    const bool known = std::isfinite(height_[s]) && std::isfinite(variance_[s]) && variance_[s] > 0;
    if (!(hole || known)) return false;
  }
  return true;
}

}  // namespace ernest::perception
