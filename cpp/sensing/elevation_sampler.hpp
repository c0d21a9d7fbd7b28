// Elevation sampling of seed 004 §4.2 / Fig. 11: 12 points, three ahead of each wheel along the
// chassis forward direction, 0.2 m apart, defined in the chassis frame; heights relative to the
// chassis so that a rover at rest on flat ground (any slope) sees zeros. Holes in the height source
// (e.g. occlusions in a stereo elevation map) are filled by linear interpolation along the
// sampling direction.
#pragma once

#include <Eigen/Core>
#include <array>

namespace ernest::sensing {

/// Where heights come from: the simulator's terrain, or an onboard elevation map. Returns false
/// where there is no data (a hole).
class HeightSource {
 public:
  virtual ~HeightSource() = default;
  virtual bool height(double x, double y, double& z) const = 0;
};

/// Regular grid of heights with NaN for missing data (an elevation map): heights(i, j) is at
/// (origin_x + i * spacing, origin_y + j * spacing). Bilinear where all four corners are known;
/// a hole elsewhere and outside the grid.
class GridHeightSource : public HeightSource {
 public:
  GridHeightSource(Eigen::MatrixXd heights, double spacing, double origin_x, double origin_y);
  bool height(double x, double y, double& z) const override;
  const Eigen::MatrixXd& heights() const { return heights_; }

 private:
  Eigen::MatrixXd heights_;
  double spacing_, origin_x_, origin_y_;
};

inline constexpr int kElevationSamples = 12;
using ElevationVector = Eigen::Matrix<double, kElevationSamples, 1>;

struct ElevationSamplingOptions {
  /// Wheel ground-contact points in the chassis frame (x forward, y left) at zero gimbal angles,
  /// rows FL, FR, RL, RR. Defaults: Table 1 wheelbase 0.86 m and track 0.80 m around the origin;
  /// the environments set them from the rover model.
  Eigen::Matrix<double, 4, 2, Eigen::RowMajor> wheel_xy =
      (Eigen::Matrix<double, 4, 2, Eigen::RowMajor>() << 0.43, 0.40, 0.43, -0.40, -0.43, 0.40,
       -0.43, -0.40).finished();
  double ground_z = -0.30;     ///< chassis-frame z of the ground under a rover at rest [m]
  double first_offset = 0.2;   ///< distance of the first point ahead of each wheel [m] (ours)
  double spacing = 0.2;        ///< between consecutive points [m] (§4.2)
  int points_per_wheel = 3;    ///< §4.2: 3 x 4 wheels = 12
  double search_step = 0.05;   ///< hole filling: step along the sampling line [m]
  double search_range = 1.0;   ///< hole filling: how far to look for valid data each way [m]
  void validate() const;
};

/// Result of one sampling: values in sample order (FL near->far, FR, RL, RR), and for each
/// sample whether it was measured (0), interpolated (1), extrapolated from one side (2), or
/// unknown and set to 0 = nominal ground (3).
struct ElevationSample {
  ElevationVector values = ElevationVector::Zero();
  std::array<int, kElevationSamples> source{};
};

class ElevationSampler {
 public:
  explicit ElevationSampler(const ElevationSamplingOptions& options = {});

  /// position: chassis origin in the world; rotation: chassis-to-world rotation matrix.
  ElevationSample sample(const Eigen::Vector3d& position, const Eigen::Matrix3d& rotation,
                         const HeightSource& source) const;

  /// Chassis-frame (x, y) of sample k (for plots and rendering).
  Eigen::Vector2d point(int k) const;
  const ElevationSamplingOptions& options() const { return options_; }

 private:
  ElevationSamplingOptions options_;
};

/// Hole filling along one line, exposed for tests and the perception pipeline: values[i] is the
/// height at distance s[i] along the line (s increasing), valid[i] says whether it is measured.
/// Missing values are linearly interpolated between the nearest valid neighbours, or held at the
/// nearest valid value beyond the ends; returns false if no value is valid.
bool fill_line(const Eigen::Ref<const Eigen::VectorXd>& s, Eigen::Ref<Eigen::VectorXd> values,
               const Eigen::Ref<const Eigen::Array<bool, Eigen::Dynamic, 1>>& valid);

}  // namespace ernest::sensing
