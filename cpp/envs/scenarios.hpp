// Terrain scenarios of seed 004 §4.5 and Table 3 (rock field, step, ripples, slope), the evaluation
// courses of §5 (Bickler trap, 20 deg slope, wheel-high step, mixed course), and the desired path and
// initial pose of each trial. Deterministic from a seed.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ernest/dynamics/terrain.hpp"
#include "ernest/sensing/path_reward.hpp"

namespace ernest::envs {

enum class ScenarioKind { Flat, RockField, Step, Ripples, Slope, BicklerTrap, SlopeEval, WheelStep, Course };

/// "flat", "rockfield", "step", "ripples", "slope", "bickler", "slope_eval", "wheel_step", "course".
ScenarioKind scenario_kind(const std::string& name);
std::string scenario_name(ScenarioKind kind);
std::vector<std::string> scenario_names();
/// The soil preset a scenario stands on unless one is chosen: Table 2's dry sand for the Bickler
/// trap (the only ground on which its rocks give seed 004 §5.2's passive outcome at every friction
/// of Table 3; benchmarks/RESULTS.md, "Bickler trap"), M90 elsewhere. The Gymnasium ids and
/// ernest_runtime both take it from here.
std::string default_soil(ScenarioKind kind);

struct ScenarioOptions {
  ScenarioKind kind = ScenarioKind::RockField;
  double grid_spacing = 0.05;  ///< height-map resolution [m]
  /// Table 3's noise amplitudes (0.1 rock field, 0.5 elsewhere) have no readable unit; we read
  /// them in decimetres, i.e. multiply by 0.1 m: 1 cm and 5 cm amplitude at the 1 m octave, mild
  /// irregularities for a 0.34 m wheel. Set 0 to remove the noise.
  double noise_unit = 0.1;
  double p_instance = 0.1;        ///< rock placement instance probability (§4.5.1)
  double max_rock_density = 0.5;  ///< [1/m^2] (Table 3)
  double clear_radius = 1.2;      ///< no rock within this distance of the start [m]
  double eval_slope_deg = 20.0;   ///< SlopeEval angle (Table 6)
  /// SlopeEval: the angle is drawn per trial, uniformly within eval_slope_deg +- this [deg]. The
  /// gimbal gaits on the slope are chaotic (travel reduction moves by several points between
  /// slopes 1 deg apart), so a comparison over seeds needs an ensemble; 0 (the default) keeps the
  /// course exactly eval_slope_deg and every seed the same episode.
  double eval_slope_spread_deg = 0.0;
  /// Multiplies every Table 3 maximum bound (ground tilt, initial yaw, lateral and heading
  /// offsets, rock and step orientations): 0 = nominal trials, 1 = the paper's ranges (curricula).
  double range_scale = 1.0;
  std::array<double, 2> step_height_range{0.2, 0.3};      ///< [m] (Table 3)
  std::array<double, 2> slope_angle_range_deg{15.0, 30.0}; ///< [deg] (Table 3)
  std::array<double, 2> ripple_amplitude_range{0.1, 0.3};  ///< [m] (Table 3)
  /// Bickler trap (§5.2): height of the row of rocks above the ground [m] and its depth along
  /// the path [m] (less than the 0.86 m wheelbase, so the rover straddles it). Defaults: the
  /// course chosen with benchmarks/bench_bickler_scan.py (see scenarios.cpp).
  double bickler_height = 0.09;
  double bickler_depth = 0.3;
  /// Coulomb friction of the obstacles (and of rigid ground), (0, 2]; nullopt (the default)
  /// draws it from Table 3's [0.5, 0.9] each trial; a value fixes it (scans, tests).
  std::optional<double> obstacle_friction;
  void validate() const;
};

/// One ripple of eq 39: one period from trough to trough starting at `start` along the ripple axis.
struct RippleSpec {
  double amplitude = 0, wavelength = 0, alpha = 0, start = 0;
};

struct Scenario {
  std::string name;
  dynamics::HeightMap terrain;
  std::vector<dynamics::BoxObstacle> obstacles;
  sensing::PathLine path;
  double start_x = 0.0, start_y = 0.0, start_heading = 0.0;
  double friction = 0.7;          ///< Coulomb friction of the obstacles (Table 3: [0.5, 0.9])
  double episode_duration = 60;   ///< [s]: 30 for the step, 60 otherwise (§4.5)
  double end_distance = 10.0;     ///< terminated once this far along the path (end of the map) [m]
  // Sampled parameters (reported in info and checked by the tests).
  double noise_amplitude = 0.0;   ///< [m], low-frequency octave
  double ground_pitch = 0.0, ground_roll = 0.0;  ///< base-plane tilt [rad]
  double rock_density = 0.0;      ///< [1/m^2]
  double step_height = 0.0, step_distance = 0.0, step_yaw = 0.0;
  std::vector<RippleSpec> ripples;
  double feature_direction = 0.0; ///< direction of the ripple/slope axis [rad]
  double slope_angle = 0.0, slope_beta_start = 0.0, slope_beta_end = 0.0, slope_length = 0.0;
  double slope_start = 0.0;       ///< distance along the slope axis where the first parabola starts
  bool slope_direct = false;      ///< the two parabolas join without a constant-slope section
  double peak_slope = 0.0;        ///< largest gradient of the slope profile [-]

  explicit Scenario(dynamics::HeightMap t) : terrain(std::move(t)) {}
};

/// Generate one trial. The rover starts at (start_x, start_y) facing start_heading; the path is a
/// straight line (eqs 33–35).
Scenario generate_scenario(const ScenarioOptions& options, std::uint64_t seed);

/// eq 39: ripple height at x for amplitude A, wavelength lambda and smoothing alpha in [0, 1).
double ripple_height(double x, double amplitude, double wavelength, double alpha);

/// Height of the §4.5.4 slope profile at distance u along its axis: flat, concave parabola
/// (beta_start), constant slope, convex parabola (beta_end), flat; the parabolas join directly
/// when `length` is too short. Also returns the peak gradient through `peak`.
double slope_height(double u, double start, double angle, double beta_start, double beta_end,
                    double length, double* peak = nullptr, bool* direct = nullptr);

}  // namespace ernest::envs
