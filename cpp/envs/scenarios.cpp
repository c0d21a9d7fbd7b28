#include "ernest/envs/scenarios.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>

#include "ernest/common/validation.hpp"
#include "ernest/envs/perlin.hpp"

namespace ernest::envs {

namespace {
constexpr double kDeg = M_PI / 180.0;

const std::vector<std::pair<ScenarioKind, std::string>>& kinds() {
  static const std::vector<std::pair<ScenarioKind, std::string>> k = {
      {ScenarioKind::Flat, "flat"},           {ScenarioKind::RockField, "rockfield"},
      {ScenarioKind::Step, "step"},           {ScenarioKind::Ripples, "ripples"},
      {ScenarioKind::Slope, "slope"},         {ScenarioKind::BicklerTrap, "bickler"},
      {ScenarioKind::SlopeEval, "slope_eval"}, {ScenarioKind::WheelStep, "wheel_step"},
      {ScenarioKind::Course, "course"}};
  return k;
}

// Uniform draws; "max bound" entries of Table 3 are symmetric ranges [-max, max].
struct Rng {
  std::mt19937_64 gen;
  double scale = 1.0;  // ScenarioOptions::range_scale, applied to the symmetric maximum bounds
  explicit Rng(std::uint64_t seed) : gen(seed) {}
  double uniform(double lo, double hi) {
    return lo == hi ? lo : std::uniform_real_distribution<double>(lo, hi)(gen);
  }
  double sym(double max) { return uniform(-max * scale, max * scale); }
  bool bernoulli(double p) { return std::uniform_real_distribution<double>(0, 1)(gen) < p; }
};

// Extent of each scenario's map in the world frame [x0, x1] x [y0, y1] (rover starts at the origin).
struct Extent {
  double x0, x1, y0, y1;
};

dynamics::HeightMap make_map(const Extent& e, double spacing,
                             const std::function<double(double, double)>& h) {
  const int nx = static_cast<int>(std::ceil((e.x1 - e.x0) / spacing)) + 1;
  const int ny = static_cast<int>(std::ceil((e.y1 - e.y0) / spacing)) + 1;
  Eigen::MatrixXd z(nx, ny);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) z(i, j) = h(e.x0 + i * spacing, e.y0 + j * spacing);
  return dynamics::HeightMap(std::move(z), spacing, e.x0, e.y0);
}

// Path through a point at `lateral` to the left of the start, heading `heading`; rover heading
// offset by `yaw`. Map end: the distance along the path to within `margin` of the map's x end.
void place_path(Scenario& s, const Extent& e, double heading, double lateral, double yaw,
                double margin = 1.5) {
  s.path = sensing::PathLine{-lateral * std::sin(heading), lateral * std::cos(heading), heading};
  s.start_x = 0.0;
  s.start_y = 0.0;
  s.start_heading = heading + yaw;
  s.end_distance = (e.x1 - margin) / std::max(std::cos(heading), 0.5);
}

dynamics::BoxObstacle box(double x, double y, double z, double lx, double ly, double lz,
                          double yaw, double pitch = 0.0, double roll = 0.0) {
  dynamics::BoxObstacle b;
  b.centre = {x, y, z};
  b.size = {lx, ly, lz};
  b.yaw = yaw;
  b.pitch = pitch;
  b.roll = roll;
  return b;
}

// An effectively infinite step (§4.5.2): its face `distance` ahead of the origin along `dir`,
// rotated by `yaw`, top `height` above `base_z`.
dynamics::BoxObstacle step_box(double distance, double dir, double yaw, double height,
                               double base_z, double pitch = 0.0, double roll = 0.0) {
  const double depth = 30.0, width = 30.0, below = 2.0;
  const double cx = distance * std::cos(dir) + 0.5 * depth * std::cos(dir + yaw);
  const double cy = distance * std::sin(dir) + 0.5 * depth * std::sin(dir + yaw);
  return box(cx, cy, base_z + height - 0.5 * (height + below), depth, width, height + below,
             dir + yaw, pitch, roll);
}
}  // namespace

ScenarioKind scenario_kind(const std::string& name) {
  for (const auto& [k, n] : kinds())
    if (n == name) return k;
  std::string allowed;
  for (const auto& [k, n] : kinds()) allowed += (allowed.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown scenario '" + name + "'; allowed: " + allowed);
}

std::string scenario_name(ScenarioKind kind) {
  for (const auto& [k, n] : kinds())
    if (k == kind) return n;
  return "unknown";
}

std::vector<std::string> scenario_names() {
  std::vector<std::string> out;
  for (const auto& kn : kinds()) out.push_back(kn.second);
  return out;
}

std::string default_soil(ScenarioKind kind) {
  return kind == ScenarioKind::BicklerTrap ? "dry_sand" : "m90";
}

void ScenarioOptions::validate() const {
  const char* o = "ScenarioOptions";
  require_in_range(o, "grid_spacing", grid_spacing, 0.01, 0.5);
  require_in_range(o, "noise_unit", noise_unit, 0.0, 1.0);
  require_in_range(o, "p_instance", p_instance, 1e-3, 1.0);
  require_in_range(o, "max_rock_density", max_rock_density, 0.0, 5.0);
  require_in_range(o, "clear_radius", clear_radius, 0.0, 10.0);
  require_in_range(o, "eval_slope_deg", eval_slope_deg, 0.0, 45.0);
  require_in_range(o, "eval_slope_spread_deg", eval_slope_spread_deg, 0.0,
                   std::min(eval_slope_deg, 45.0 - eval_slope_deg));
  require_in_range(o, "range_scale", range_scale, 0.0, 1.0);
  require_in_range(o, "step_height_range[0]", step_height_range[0], 0.0, 1.0);
  require_in_range(o, "step_height_range[1]", step_height_range[1], step_height_range[0], 1.0);
  require_in_range(o, "slope_angle_range_deg[0]", slope_angle_range_deg[0], 0.0, 40.0);
  require_in_range(o, "slope_angle_range_deg[1]", slope_angle_range_deg[1], slope_angle_range_deg[0], 40.0);
  require_in_range(o, "ripple_amplitude_range[0]", ripple_amplitude_range[0], 0.0, 1.0);
  require_in_range(o, "ripple_amplitude_range[1]", ripple_amplitude_range[1], ripple_amplitude_range[0], 1.0);
  require_in_range(o, "bickler_height", bickler_height, 0.02, 0.5);
  // straddled: the front wheels (0.34 m) must fit beyond the rocks while the rear ones are before
  require_in_range(o, "bickler_depth", bickler_depth, 0.05, 0.6);
  if (obstacle_friction) {
    require_positive(o, "obstacle_friction", *obstacle_friction);
    require_in_range(o, "obstacle_friction", *obstacle_friction, 0.0, 2.0);
  }
}

double ripple_height(double x, double a, double lambda, double alpha) {
  require_in_range("ripple_height", "alpha", alpha, 0.0, 0.99);
  require_positive("ripple_height", "wavelength", lambda);
  // eq 39: alpha = 0 triangular, alpha -> 1 sinusoidal; the profile spans [0, A].
  const double num = 1.0 - 2.0 / M_PI * std::acos((1.0 - alpha) * std::sin(2.0 * M_PI * x / lambda));
  const double den = 1.0 - 2.0 / M_PI * std::acos(1.0 - alpha);
  return 0.5 * a * (num / den + 1.0);
}

double slope_height(double u, double start, double angle, double bs, double be, double length,
                    double* peak, bool* direct) {
  const double t = std::tan(angle);
  double a = t / (2.0 * bs), b = t / (2.0 * be), c = length - a - b, g = t;
  const bool is_direct = c < 0.0;
  if (is_direct) {  // §4.5.4: too short, the parabolas meet where their gradients match
    a = length * be / (bs + be);
    b = length * bs / (bs + be);
    c = 0.0;
    g = 2.0 * bs * a;
  }
  if (peak) *peak = g;
  if (direct) *direct = is_direct;
  const double s = u - start;
  if (s <= 0.0) return 0.0;
  if (s <= a) return bs * s * s;
  const double z1 = bs * a * a;
  if (s <= a + c) return z1 + g * (s - a);
  const double z2 = z1 + g * c, r = std::min(s - a - c, b);
  return z2 + g * r - be * r * r;
}

Scenario generate_scenario(const ScenarioOptions& options, std::uint64_t seed) {
  options.validate();
  Rng rng(seed);
  rng.scale = options.range_scale;
  const ScenarioKind kind = options.kind;
  const double sp = options.grid_spacing;
  // Table 3 "Ground / Noise amplitude": 0.1 for the rock field, 0.5 elsewhere.
  double noise_amp = (kind == ScenarioKind::RockField ? 0.1 : 0.5) * options.noise_unit;
  if (kind == ScenarioKind::Flat || kind == ScenarioKind::SlopeEval ||
      kind == ScenarioKind::BicklerTrap || kind == ScenarioKind::WheelStep) {
    noise_amp = 0.0;  // evaluation courses are clean so runs compare like with like
  }
  const TerrainNoise noise(rng.gen(), noise_amp);

  Extent e{-3.0, 14.0, -6.0, 6.0};
  double heading = 0.0, lateral = 0.0, yaw = 0.0, duration = 60.0;
  std::function<double(double, double)> base = [](double, double) { return 0.0; };
  double pitch = 0.0, roll = 0.0, feature_dir = 0.0, s_angle = 0.0, s_bs = 0.0, s_be = 0.0,
         s_len = 0.0, s_start = 0.0;
  std::vector<RippleSpec> ripples;

  switch (kind) {
    case ScenarioKind::RockField:
      pitch = rng.sym(5.0 * kDeg);  // Table 3: ground pitch and roll up to 5 deg
      roll = rng.sym(5.0 * kDeg);
      yaw = rng.sym(180.0 * kDeg);
      lateral = rng.sym(2.0);
      e = {-5.0, 14.0, -7.0, 7.0};
      base = [tp = std::tan(pitch), tr = std::tan(roll)](double x, double y) {
        return tp * x + tr * y;
      };
      break;
    case ScenarioKind::Step:
      yaw = rng.sym(45.0 * kDeg);
      lateral = rng.sym(1.0);
      duration = 30.0;
      e = {-3.0, 9.0, -5.0, 5.0};
      break;
    case ScenarioKind::Ripples:
    case ScenarioKind::Slope:
      yaw = rng.sym(45.0 * kDeg);
      lateral = rng.sym(1.0);
      heading = rng.sym(20.0 * kDeg);  // path at up to 20 deg to the ripples / the slope
      break;
    case ScenarioKind::Course:
      duration = 180.0;
      e = {-3.0, 30.0, -4.0, 4.0};
      break;
    case ScenarioKind::SlopeEval:
      e = {-3.0, 16.0, -4.0, 4.0};
      break;
    default:
      e = {-3.0, 12.0, -4.0, 4.0};
      break;
  }

  if (kind == ScenarioKind::Ripples || kind == ScenarioKind::Course) {
    double u = kind == ScenarioKind::Course ? 6.0 : 1.5;  // start of the first ripple
    const int count = kind == ScenarioKind::Course ? 3 : 4;
    for (int i = 0; i < count; ++i) {
      RippleSpec r;
      r.amplitude = kind == ScenarioKind::Course ? 0.2 : rng.uniform(options.ripple_amplitude_range[0],
                                                                 options.ripple_amplitude_range[1]);
      r.wavelength = kind == ScenarioKind::Course ? 0.8 : rng.uniform(0.6, 1.0);
      r.alpha = kind == ScenarioKind::Course ? 0.1 : rng.uniform(0.0, 0.2);
      r.start = u;
      u += r.wavelength;
      ripples.push_back(r);
    }
  }
  if (kind == ScenarioKind::Slope) {
    s_angle = rng.uniform(options.slope_angle_range_deg[0] * kDeg,
                          options.slope_angle_range_deg[1] * kDeg);
    s_bs = rng.uniform(0.1, 0.5);
    s_len = rng.uniform(1.5, 3.0);
    s_be = rng.uniform(0.2, 2.0);
    s_start = 1.5;
  } else if (kind == ScenarioKind::SlopeEval) {
    s_angle = options.eval_slope_deg * kDeg;
    if (options.eval_slope_spread_deg > 0.0) {  // not a Table 3 bound: range_scale leaves it
      const double spread = options.eval_slope_spread_deg * kDeg;
      s_angle += rng.uniform(-spread, spread);
    }
    s_bs = 0.5;
    s_be = 2.0;
    s_len = 12.0;  // long constant-slope section: the whole run is on the slope
    // The rover starts on the constant slope (Table 6 compares climbing on it): the transition
    // (0.36 m) ends 1.1 m behind the start, so no flat approach counts as progress.
    s_start = -1.5;
  } else if (kind == ScenarioKind::Course) {
    s_angle = 15.0 * kDeg;
    s_bs = 0.5;
    s_be = 1.0;
    s_len = 4.0;
    s_start = 12.0;
  }

  auto height = [&](double x, double y) {
    // Ripples and slope along the feature axis (the world x axis here).
    double z = base(x, y);
    const double u = x * std::cos(feature_dir) + y * std::sin(feature_dir);
    for (const RippleSpec& r : ripples) {
      if (u >= r.start && u < r.start + r.wavelength) {
        z += ripple_height(u - r.start - 0.25 * r.wavelength, r.amplitude, r.wavelength, r.alpha);
      }
    }
    if (s_angle > 0.0) z += slope_height(u, s_start, s_angle, s_bs, s_be, s_len);
    return z + noise(x, y);
  };

  Scenario s(make_map(e, sp, height));
  s.name = scenario_name(kind);
  s.episode_duration = duration;
  s.noise_amplitude = noise_amp;
  s.ground_pitch = pitch;
  s.ground_roll = roll;
  s.ripples = ripples;
  s.feature_direction = feature_dir;
  if (s_angle > 0.0) {
    s.slope_angle = s_angle;
    s.slope_beta_start = s_bs;
    s.slope_beta_end = s_be;
    s.slope_length = s_len;
    s.slope_start = s_start;
    slope_height(0.0, s_start, s_angle, s_bs, s_be, s_len, &s.peak_slope, &s.slope_direct);
  }
  s.friction = rng.uniform(0.5, 0.9);  // Table 3 contacts (drawn always: same later draws)
  if (options.obstacle_friction) s.friction = *options.obstacle_friction;
  place_path(s, e, heading, lateral, yaw);

  switch (kind) {
    case ScenarioKind::RockField: {
      // §4.5.1: cells of area p / rho (so that the mean density is rho; the printed p^2 / rho would
      // give rho / p), one rock with probability p, uniform in its cell, centre on the surface.
      s.rock_density = rng.uniform(0.0, options.max_rock_density);
      if (s.rock_density > 0.0) {
        const double cell = std::sqrt(options.p_instance / s.rock_density);
        for (double cx = e.x0; cx < e.x1; cx += cell) {
          for (double cy = e.y0; cy < e.y1; cy += cell) {
            if (!rng.bernoulli(options.p_instance)) continue;
            const double x = cx + rng.uniform(0.0, cell), y = cy + rng.uniform(0.0, cell);
            const double lx = rng.uniform(0.2, 0.4), ly = rng.uniform(0.2, 0.6),
                         lz = rng.uniform(0.2, 0.6);
            const double ryaw = rng.sym(90.0 * kDeg), rp = rng.sym(20.0 * kDeg),
                         rr = rng.sym(20.0 * kDeg);
            if (x > e.x1 - 0.5 || y > e.y1 - 0.5 || x < e.x0 + 0.5 || y < e.y0 + 0.5) continue;
            if (std::hypot(x - s.start_x, y - s.start_y) < options.clear_radius) continue;
            s.obstacles.push_back(box(x, y, s.terrain.height(x, y), lx, ly, lz, ryaw, rp, rr));
          }
        }
      }
      break;
    }
    case ScenarioKind::Step:
    case ScenarioKind::WheelStep: {
      const bool eval = kind == ScenarioKind::WheelStep;
      s.step_height = eval ? 0.34  // wheel-high = wheel diameter
                           : rng.uniform(options.step_height_range[0], options.step_height_range[1]);
      s.step_distance = eval ? 1.4 : rng.uniform(1.2, 1.6);
      s.step_yaw = eval ? 0.0 : rng.sym(20.0 * kDeg);
      const double sp_pitch = eval ? 0.0 : rng.sym(1.0 * kDeg), sp_roll = eval ? 0.0 : rng.sym(1.0 * kDeg);
      // The step is placed ahead of the rover's initial pose (§4.5.2).
      const double fx = s.step_distance * std::cos(s.start_heading);
      const double fy = s.step_distance * std::sin(s.start_heading);
      s.obstacles.push_back(step_box(s.step_distance, s.start_heading, s.step_yaw, s.step_height,
                                     s.terrain.height(fx, fy), sp_pitch, sp_roll));
      break;
    }
    case ScenarioKind::BicklerTrap: {
      // Seed 004 §5.2: a continuous row of rocks across the path that the rover can straddle
      // (depth along the path less than the 0.86 m wheelbase), 3 m wide, six 0.5 m rocks whose
      // tops differ by up to +-5 mm. Height and depth: ScenarioOptions::bickler_height and
      // bickler_depth, by default 0.09 m x 0.3 m, chosen with benchmarks/bench_bickler_scan.py
      // (height x friction x ground): on dry sand, the ground ernest/BicklerTrap-v0 registers,
      // 0.07-0.11 m rows give Fig. 17's passive outcome (front wheels over, rear wheels not,
      // no reversing out) at every friction of Table 3; 0.09 m is the middle. M90, wet sand and
      // rigid ground have no such height (benchmarks/RESULTS.md, "Bickler trap").
      const double h = options.bickler_height, d = options.bickler_depth;
      for (int i = 0; i < 6; ++i) {
        const double y = -1.25 + 0.5 * i;
        s.obstacles.push_back(box(1.6, y, 0.0, d, 0.5, 2.0 * h + rng.uniform(-0.01, 0.01), 0.0));
      }
      break;
    }
    case ScenarioKind::Course: {
      // Rocks from 2 to 5 m, ripples from 6 m, a 15 deg slope from 12 m, a 0.2 m step on top.
      for (double x = 2.2; x < 5.0; x += 0.9) {
        for (double y = -1.2; y <= 1.2; y += 1.2) {
          const double jx = x + rng.uniform(-0.2, 0.2), jy = y + rng.uniform(-0.2, 0.2);
          s.obstacles.push_back(box(jx, jy, s.terrain.height(jx, jy), rng.uniform(0.2, 0.3),
                                    rng.uniform(0.2, 0.3), rng.uniform(0.15, 0.25),
                                    rng.sym(45.0 * kDeg)));
        }
      }
      const double top = slope_height(1e3, s_start, s_angle, s_bs, s_be, s_len);
      s.obstacles.push_back(step_box(21.0, 0.0, 0.0, 0.2, top));
      break;
    }
    default:
      break;
  }
  return s;
}

}  // namespace ernest::envs
