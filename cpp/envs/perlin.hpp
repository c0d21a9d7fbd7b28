// Two-dimensional gradient (Perlin) noise, deterministic from a seed, and the two-octave terrain
// irregularities of seed 004 §4.5 (periods 1 m and 0.5 m, the second at half amplitude).
#pragma once

#include <array>
#include <cstdint>

namespace ernest::envs {

class PerlinNoise {
 public:
  explicit PerlinNoise(std::uint64_t seed);
  /// Noise at (x, y) in lattice units: 0 at integer points, |value| <= ~0.71, C1-smooth (quintic fade).
  double operator()(double x, double y) const;

 private:
  std::array<int, 512> perm_{};
};

/// amplitude * n1(x / 1 m, y / 1 m) + amplitude / 2 * n2(x / 0.5 m, y / 0.5 m), independent octaves.
class TerrainNoise {
 public:
  TerrainNoise(std::uint64_t seed, double amplitude, double period1 = 1.0, double period2 = 0.5);
  double operator()(double x, double y) const;
  double amplitude() const { return amplitude_; }

 private:
  PerlinNoise n1_, n2_;
  double amplitude_, period1_, period2_;
};

}  // namespace ernest::envs
