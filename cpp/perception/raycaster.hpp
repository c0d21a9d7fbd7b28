// Simulated camera images of the simulator's terrain (seed 004 §2.4 needs stereo images; the paper's
// DARTS renders them, we ray-cast): a deterministic CPU ray caster over the height map (bilinear
// surface, as the dynamics sees it) and the rigid boxes, returning a textured grey image and the
// exact depth. The texture is procedural value noise of the world position (so it does not swim
// between the two cameras or between frames), band-limited to the pixel footprint (no aliasing,
// which would make the left and right images disagree), Lambertian-shaded under a fixed sun, plus
// seeded Gaussian sensor noise.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "ernest/dynamics/terrain.hpp"
#include "ernest/perception/camera.hpp"

namespace ernest::perception {

using GrayImage = Eigen::Matrix<std::uint8_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using FloatImage = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct RenderOptions {
  double texture_wavelength = 0.32;  ///< coarsest texture octave [m] (ours)
  int texture_octaves = 5;           ///< each half the wavelength of the last (0.32 ... 0.02 m)
  double texture_gain = 0.8;         ///< amplitude ratio between consecutive octaves
  double albedo = 0.55;              ///< mean albedo
  double contrast = 0.45;            ///< albedo = albedo * (1 + contrast * noise), noise in ~[-1, 1]
  double ambient = 0.35;             ///< share of ambient light
  double sun_elevation = 0.8;        ///< [rad]
  double sun_azimuth = 0.6;          ///< [rad] from +x towards +y
  double noise_sigma = 1.5;          ///< Gaussian sensor noise [grey levels]
  double sky = 200.0;                ///< grey level where no surface is hit
  double max_range = 30.0;           ///< [m] along the ray
  std::uint64_t seed = 0;            ///< texture and noise seed
  void validate() const;
};

class Raycaster {
 public:
  /// Copies the terrain and the boxes (the scene is immutable afterwards).
  Raycaster(const dynamics::HeightMap& terrain, const std::vector<dynamics::BoxObstacle>& boxes,
            const RenderOptions& options = {});

  /// Renders one camera (pose: camera -> world, camera frame x right, y down, z forward):
  /// image (grey levels) and depth (z along the optical axis [m]; NaN where nothing is hit).
  /// frame selects the sensor-noise draw (same frame -> same image). Resizes the outputs.
  void render(const Eigen::Isometry3d& pose, const StereoCameraParameters& camera,
              std::uint64_t frame, GrayImage& image, FloatImage& depth) const;

  /// First hit of the ray o + t d (d unit) with the scene: t, and the unit normal; false if
  /// none within max_range.
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& t,
                 Eigen::Vector3d& normal) const;
  /// Height of the top surface (terrain or box top) at (x, y): a vertical ray cast from above.
  double surface_height(double x, double y) const;
  /// Band-limited texture value in ~[-1, 1] at a world point for a footprint [m].
  double texture(const Eigen::Vector3d& p, double footprint) const;

  const dynamics::HeightMap& terrain() const { return terrain_; }
  const RenderOptions& options() const { return options_; }
  double lipschitz() const { return lipschitz_; }

 private:
  struct Box {
    Eigen::Matrix3d rt;  // world -> box rotation
    Eigen::Vector3d centre, half;
    double radius;
  };
  bool intersect_terrain(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max,
                         double& t) const;
  // intersect() over a subset of the boxes (the candidates of one image tile)
  bool intersect_boxes(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& t,
                       Eigen::Vector3d& normal, const int* boxes, int count) const;

  dynamics::HeightMap terrain_;
  std::vector<Box> boxes_;
  std::vector<int> all_boxes_;  // 0 .. n-1
  RenderOptions options_;
  double lipschitz_ = 0.0;  // bound on |grad h| of the bilinear surface
  double top_ = 0.0;        // above every surface
  Eigen::Vector3d sun_;
};

}  // namespace ernest::perception
