#include "ernest/envs/perlin.hpp"

#include <cmath>
#include <numeric>
#include <random>

#include "ernest/common/validation.hpp"

namespace ernest::envs {

PerlinNoise::PerlinNoise(std::uint64_t seed) {
  std::array<int, 256> p{};
  std::iota(p.begin(), p.end(), 0);
  std::mt19937_64 rng(seed);
  for (int i = 255; i > 0; --i) {  // Fisher–Yates with our own draws: identical on every platform
    const int j = static_cast<int>(rng() % static_cast<std::uint64_t>(i + 1));
    std::swap(p[i], p[j]);
  }
  for (int i = 0; i < 512; ++i) perm_[i] = p[i & 255];
}

namespace {
inline double fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }
inline double grad(int h, double x, double y) {
  // Eight unit-ish gradient directions.
  switch (h & 7) {
    case 0: return x + y;
    case 1: return x - y;
    case 2: return -x + y;
    case 3: return -x - y;
    case 4: return x;
    case 5: return -x;
    case 6: return y;
    default: return -y;
  }
}
}  // namespace

double PerlinNoise::operator()(double x, double y) const {
  const double fx = std::floor(x), fy = std::floor(y);
  const int xi = static_cast<int>(static_cast<long long>(fx) & 255);
  const int yi = static_cast<int>(static_cast<long long>(fy) & 255);
  const double dx = x - fx, dy = y - fy;
  const double u = fade(dx), v = fade(dy);
  const int aa = perm_[perm_[xi] + yi], ab = perm_[perm_[xi] + yi + 1];
  const int ba = perm_[perm_[xi + 1] + yi], bb = perm_[perm_[xi + 1] + yi + 1];
  const double x1 = grad(aa, dx, dy) + u * (grad(ba, dx - 1, dy) - grad(aa, dx, dy));
  const double x2 = grad(ab, dx, dy - 1) + u * (grad(bb, dx - 1, dy - 1) - grad(ab, dx, dy - 1));
  return 0.5 * (x1 + v * (x2 - x1));  // 0.5: gradients of length up to sqrt(2)
}

TerrainNoise::TerrainNoise(std::uint64_t seed, double amplitude, double period1, double period2)
    : n1_(seed * 2654435761ULL + 1), n2_(seed * 2654435761ULL + 2), amplitude_(amplitude),
      period1_(period1), period2_(period2) {
  require_in_range("TerrainNoise", "amplitude", amplitude, 0.0, 10.0);
  require_positive("TerrainNoise", "period1", period1);
  require_positive("TerrainNoise", "period2", period2);
}

double TerrainNoise::operator()(double x, double y) const {
  if (amplitude_ == 0.0) return 0.0;
  return amplitude_ * n1_(x / period1_, y / period1_) +
         0.5 * amplitude_ * n2_(x / period2_, y / period2_);
}

}  // namespace ernest::envs
