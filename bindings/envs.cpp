// Python bindings of cpp/envs: scenarios, the episode core RoverEnv and the batched VecRoverEnv.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "ernest/envs/rover_env.hpp"
#include "ernest/envs/scenarios.hpp"
#include "ernest/envs/vec_env.hpp"
#include "exclusive.hpp"
#include "interrupt.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::envs;

namespace {
py::dict result_info(const StepResult& r, const RoverEnv& e) {
  py::dict d;
  d["progress"] = r.reward.progress;
  d["path_progress"] = e.metrics().progress;  // distance along the path since the start [m]
  d["lateral_deviation"] = r.reward.lateral;
  d["reward_progress"] = r.reward.progress_term;
  d["reward_lateral"] = r.reward.lateral_term;
  d["reward_torque"] = r.reward.torque_term;
  d["diverged"] = r.diverged;
  d["message"] = r.message;
  return d;
}

py::dict metrics_dict(const EpisodeMetrics& m, double mass) {
  py::dict d;
  d["time"] = m.time;
  d["progress"] = m.progress;
  d["expected_progress"] = m.expected_progress;
  d["distance"] = m.distance;
  d["energy"] = m.energy;
  d["mean_abs_roll_torque"] = m.mean_abs_roll_torque;
  d["travel_reduction"] = m.travel_reduction();
  d["cost_of_transport"] = m.cost_of_transport(mass);
  return d;
}

// Obstacles as rows (cx, cy, cz, lx, ly, lz, yaw, pitch, roll) for numpy users and plots.
Eigen::Matrix<double, Eigen::Dynamic, 9, Eigen::RowMajor> obstacle_rows(const Scenario& s) {
  Eigen::Matrix<double, Eigen::Dynamic, 9, Eigen::RowMajor> o(s.obstacles.size(), 9);
  for (size_t i = 0; i < s.obstacles.size(); ++i) {
    const auto& b = s.obstacles[i];
    o.row(i) << b.centre.x(), b.centre.y(), b.centre.z(), b.size.x(), b.size.y(), b.size.z(), b.yaw,
        b.pitch, b.roll;
  }
  return o;
}
// What a RoverEnv call may touch: the env and the stereo pipeline it hands out (env.mapper and
// env.mapper.map), so that a second thread is refused on any of them (exclusive.hpp).
std::vector<const void*> env_objects(const RoverEnv& e) {
  const perception::StereoMapper* m = e.mapper();
  return {&e, m, m != nullptr ? static_cast<const void*>(&m->map()) : nullptr};
}

// A VecRoverEnv call touches every env (vec.env(i) hands them out) and what they hand out.
std::vector<const void*> vec_objects(VecRoverEnv& v) {
  std::vector<const void*> all{&v};
  for (int i = 0; i < v.size(); ++i) {
    const std::vector<const void*> e = env_objects(v.env(i));
    all.insert(all.end(), e.begin(), e.end());
  }
  return all;
}

// A RoverEnv getter under the guard.
template <class R>
auto env_getter(const char* what, R (*f)(const RoverEnv&)) {
  return [what, f](const RoverEnv& e) -> R {
    const Busy busy(what, env_objects(e));
    return f(e);
  };
}
}  // namespace

void bind_envs(py::module_& m) {
  py::class_<ScenarioOptions>(m, "ScenarioOptions", "Scenario generation settings (§4.5, Table 3).")
      .def(py::init<>())
      .def_property("kind", [](const ScenarioOptions& o) { return scenario_name(o.kind); },
                    [](ScenarioOptions& o, const std::string& n) { o.kind = scenario_kind(n); },
                    "scenario name (see scenario_names())")
      .def_readwrite("grid_spacing", &ScenarioOptions::grid_spacing, "[m]")
      .def_readwrite("noise_unit", &ScenarioOptions::noise_unit,
                     "metres per Table 3 noise-amplitude unit (ours: 0.1)")
      .def_readwrite("p_instance", &ScenarioOptions::p_instance)
      .def_readwrite("max_rock_density", &ScenarioOptions::max_rock_density, "[1/m^2]")
      .def_readwrite("clear_radius", &ScenarioOptions::clear_radius, "[m]")
      .def_readwrite("eval_slope_deg", &ScenarioOptions::eval_slope_deg, "[deg]")
      .def_readwrite("eval_slope_spread_deg", &ScenarioOptions::eval_slope_spread_deg,
                     "[deg] SlopeEval angle drawn per trial within eval_slope_deg +- this (0: fixed)")
      .def_readwrite("range_scale", &ScenarioOptions::range_scale,
                     "multiplies Table 3's maximum bounds (tilt, yaw/lateral/heading offsets, "
                     "orientations); 0..1")
      .def_readwrite("step_height_range", &ScenarioOptions::step_height_range, "(min, max) [m]")
      .def_readwrite("slope_angle_range_deg", &ScenarioOptions::slope_angle_range_deg,
                     "(min, max) [deg]")
      .def_readwrite("ripple_amplitude_range", &ScenarioOptions::ripple_amplitude_range,
                     "(min, max) [m]")
      .def_readwrite("bickler_height", &ScenarioOptions::bickler_height,
                     "Bickler trap: height of the row of rocks [m], 0.02..0.5")
      .def_readwrite("bickler_depth", &ScenarioOptions::bickler_depth,
                     "Bickler trap: depth of the row along the path [m], 0.05..0.6 (less than the "
                     "0.86 m wheelbase: the rover straddles it)")
      .def_readwrite("obstacle_friction", &ScenarioOptions::obstacle_friction,
                     "Coulomb friction of the obstacles and rigid ground, (0, 2]; None (default) "
                     "draws it from Table 3's [0.5, 0.9] each trial")
      .def("validate", &ScenarioOptions::validate, "Raise ValueError on an invalid field.");

  py::class_<RippleSpec>(m, "RippleSpec", "One ripple of eq 39.")
      .def_readonly("amplitude", &RippleSpec::amplitude)
      .def_readonly("wavelength", &RippleSpec::wavelength)
      .def_readonly("alpha", &RippleSpec::alpha)
      .def_readonly("start", &RippleSpec::start);

  py::class_<Scenario, std::shared_ptr<Scenario>>(m, "Scenario", "A generated trial: terrain, obstacles, path, start pose.")
      .def_readonly("name", &Scenario::name)
      .def_property_readonly("heights", [](const Scenario& s) { return s.terrain.heights(); },
                             "height grid (nx x ny) [m]")
      .def_property_readonly("spacing", [](const Scenario& s) { return s.terrain.spacing(); })
      .def_property_readonly("origin", [](const Scenario& s) {
        return py::make_tuple(s.terrain.origin_x(), s.terrain.origin_y());
      })
      .def("height", [](const Scenario& s, double x, double y) { return s.terrain.height(x, y); },
           "x"_a, "y"_a, "Bilinear terrain height [m].")
      .def_property_readonly("obstacles", &obstacle_rows,
                             "rows (cx, cy, cz, lx, ly, lz, yaw, pitch, roll)")
      .def_readonly("path", &Scenario::path)
      .def_readonly("start_x", &Scenario::start_x)
      .def_readonly("start_y", &Scenario::start_y)
      .def_readonly("start_heading", &Scenario::start_heading)
      .def_readonly("friction", &Scenario::friction)
      .def_readonly("episode_duration", &Scenario::episode_duration)
      .def_readonly("end_distance", &Scenario::end_distance)
      .def_readonly("noise_amplitude", &Scenario::noise_amplitude)
      .def_readonly("ground_pitch", &Scenario::ground_pitch)
      .def_readonly("ground_roll", &Scenario::ground_roll)
      .def_readonly("rock_density", &Scenario::rock_density)
      .def_readonly("step_height", &Scenario::step_height)
      .def_readonly("step_distance", &Scenario::step_distance)
      .def_readonly("step_yaw", &Scenario::step_yaw)
      .def_readonly("ripples", &Scenario::ripples)
      .def_readonly("slope_angle", &Scenario::slope_angle)
      .def_readonly("slope_beta_start", &Scenario::slope_beta_start)
      .def_readonly("slope_beta_end", &Scenario::slope_beta_end)
      .def_readonly("slope_length", &Scenario::slope_length)
      .def_readonly("slope_start", &Scenario::slope_start)
      .def_readonly("slope_direct", &Scenario::slope_direct)
      .def_readonly("peak_slope", &Scenario::peak_slope);

  m.def("generate_scenario", &generate_scenario, "options"_a, "seed"_a,
        "Generate one trial deterministically from a seed.");
  m.def("scenario_names", &scenario_names, "Names accepted by ScenarioOptions.kind.");
  m.def("default_soil", [](const std::string& name) { return default_soil(scenario_kind(name)); },
        "scenario"_a,
        "The soil preset the scenario stands on unless one is chosen: 'dry_sand' for the Bickler "
        "trap, 'm90' elsewhere (ernest_runtime --scenario takes the same).");
  m.def("ripple_height", &ripple_height, "x"_a, "amplitude"_a, "wavelength"_a, "alpha"_a, "eq 39");

  py::class_<EnvOptions>(m, "EnvOptions", "Options of one ERNEST episode (see rover_env.hpp).")
      .def(py::init<>())
      .def_readwrite("scenario", &EnvOptions::scenario)
      .def_readwrite("soil", &EnvOptions::soil, "'dry_sand', 'm90' or 'wet_sand'")
      .def_readwrite("rigid_ground", &EnvOptions::rigid_ground)
      .def_readwrite("eps_slip", &EnvOptions::eps_slip, "eq 12 regularisation [(m/s)^-2], > 0; None: the soil preset's")
      .def_readwrite("eps_motion", &EnvOptions::eps_motion, "eq 16 rest threshold [m/s], > 0; None: the soil preset's")
      .def_readwrite("passive", &EnvOptions::passive, "gimbal off, clutch open")
      .def_readwrite("physics_dt", &EnvOptions::physics_dt, "[s], (0, 0.05]; None: the simulator's default")
      .def_readwrite("slip_force_tolerance", &EnvOptions::slip_force_tolerance,
                     "implicit slip tolerance (SimOptions.slip_force_tolerance); None: its default")
      .def_readwrite("obstacle_substeps", &EnvOptions::obstacle_substeps,
                     "substeps while touching an obstacle (SimOptions.obstacle_substeps), 1..64; None: its default")
      .def_readwrite("policy_dt", &EnvOptions::policy_dt, "[s]")
      .def_readwrite("episode_duration", &EnvOptions::episode_duration, "[s], (0, 3600]; None: the scenario's")
      .def_readwrite("sync_rate", &EnvOptions::sync_rate, "[Hz]")
      .def_readwrite("fts_noise_force", &EnvOptions::fts_noise_force, "[N]")
      .def_readwrite("fts_noise_torque", &EnvOptions::fts_noise_torque, "[N m]")
      .def_readwrite("start_speed", &EnvOptions::start_speed, "[m/s]")
      .def_readwrite("terrain_source", &EnvOptions::terrain_source,
                     "'truth' (default) or 'stereo' (elevation samples from the fused stereo map)")
      .def_readwrite("stereo", &EnvOptions::stereo, "perception.StereoMapperOptions")
      .def_readwrite("scales", &EnvOptions::scales)
      .def_readwrite("weights", &EnvOptions::weights)
      .def_readwrite("limits", &EnvOptions::limits)
      .def("validate", &EnvOptions::validate, "Raise ValueError on an invalid field.");

  py::class_<RoverEnv>(m, "RoverEnv", "One ERNEST episode: scenario, simulator, sensing, reward.")
      .def(py::init<const dynamics::RoverParameters&, const EnvOptions&>(), "params"_a, "options"_a)
      .def("reset",
           [](RoverEnv& e, std::uint64_t seed) {
             const Busy busy("RoverEnv.reset", env_objects(e));
             py::gil_scoped_release release;
             return e.reset(seed);
           },
           "seed"_a,
           "New trial from a seed; returns the 45 observation values.")
      .def("reset_next",
           [](RoverEnv& e) {
             const Busy busy("RoverEnv.reset_next", env_objects(e));
             py::gil_scoped_release release;
             return e.reset_next();
           },
           "New trial with the next seed of the sequence started by reset(seed).")
      .def("step",
           [](RoverEnv& e, const sensing::ActionVector& action) {
             const Busy busy("RoverEnv.step", env_objects(e));
             StepResult r;
             {
               py::gil_scoped_release release;
               r = e.step(action);
             }
             return py::make_tuple(r.observation, r.reward.reward, r.terminated, r.truncated,
                                   result_info(r, e));
           },
           "action"_a, "One policy step: (obs, reward, terminated, truncated, info).")
      // Shared, not a reference into the env: reset() replaces the scenario, and a holder keeps
      // the old one.
      .def_property_readonly("scenario", env_getter("RoverEnv.scenario", +[](const RoverEnv& e) {
        if (!e.shared_scenario()) throw std::logic_error("RoverEnv: call reset() first");
        return std::const_pointer_cast<Scenario>(e.shared_scenario());
      }), "the episode's Scenario (shared; after the next reset() it stays the old episode's)")
      .def_property_readonly("metrics", env_getter("RoverEnv.metrics", +[](const RoverEnv& e) {
        return metrics_dict(e.metrics(), e.parameters().total_mass());
      }), "the episode's metrics so far; cost_of_transport is inf until the rover has made progress")
      .def_property_readonly("episode_seed", &RoverEnv::episode_seed)
      .def_property_readonly("done", &RoverEnv::done)
      .def_property_readonly("substeps", &RoverEnv::substeps)
      .def_property_readonly("elevation", env_getter("RoverEnv.elevation", +[](const RoverEnv& e) {
        return Eigen::VectorXd(e.elevation().values);
      }), "last elevation samples [m]")
      .def_property_readonly("elevation_points", env_getter("RoverEnv.elevation_points", +[](const RoverEnv& e) {
        Eigen::Matrix<double, sensing::kElevationSamples, 2, Eigen::RowMajor> p;
        for (int k = 0; k < sensing::kElevationSamples; ++k) p.row(k) = e.sampler().point(k).transpose();
        return p;
      }), "chassis-frame (x, y) of the 12 samples [m]")
      .def_property_readonly("elevation_source", env_getter("RoverEnv.elevation_source", +[](const RoverEnv& e) {
        return std::vector<int>(e.elevation().source.begin(), e.elevation().source.end());
      }), "per sample: 0 measured, 1 interpolated, 2 extrapolated, 3 unknown (hole-filling of §4.2)")
      .def_property_readonly("mapper", env_getter("RoverEnv.mapper", +[](const RoverEnv& e) {
        return e.shared_mapper();
      }), "the episode's perception.StereoMapper (terrain_source 'stereo'), else None; shared: "
          "after the next reset() it is a detached pipeline of the old episode")
      .def_property_readonly("fts", env_getter("RoverEnv.fts", +[](const RoverEnv& e) { return e.fts(); }), "last processed force–torque values (4 x 6)")
      .def_property_readonly("fts_bias", env_getter("RoverEnv.fts_bias", +[](const RoverEnv& e) { return e.fts_bias(); }))
      .def_property_readonly("current_action", env_getter("RoverEnv.current_action", +[](const RoverEnv& e) {
        return e.current_action();
      }))
      .def_property_readonly("sim", env_getter("RoverEnv.sim", +[](const RoverEnv& e) {
        if (!e.shared_sim()) throw std::logic_error("RoverEnv: call reset() first");
        return e.shared_sim();
      }), "the episode's dynamics.RoverSim (shared): command and step it directly, e.g. with "
         "dynamics.sync_commands to drive backwards (the action's V_x is 0..0.2 m/s); after the "
         "next reset() it is a detached simulator of the old episode")
      .def_property_readonly("state", env_getter("RoverEnv.state", +[](const RoverEnv& e) {
        return e.sim().state_copy();
      }),
                             "ground truth of the rover: dynamics.RoverState (a copy), the type "
                             "RoverSim.state gives");

  py::class_<VecRoverEnv>(m, "VecRoverEnv",
                          "N RoverEnv episodes stepped in parallel (next-step autoreset).")
      .def(py::init<const dynamics::RoverParameters&, const EnvOptions&, int, int>(), "params"_a,
           "options"_a, "num_envs"_a, "num_threads"_a)
      .def("reset",
           [](VecRoverEnv& v, const std::vector<std::uint64_t>& seeds) {
             const Busy busy("VecRoverEnv.reset", vec_objects(v));
             py::gil_scoped_release release;
             interruptible scope;
             return v.reset(seeds);
           },
           "seeds"_a,
           "Reset env i from seeds[i]; returns num_envs x 45 observations.")
      .def("step",
           [](VecRoverEnv& v, const Eigen::Ref<const ActionBatch>& actions) {
             const Busy busy("VecRoverEnv.step", vec_objects(v));
             ObservationBatch obs(v.size(), sensing::kObservationSize);
             std::vector<StepResult> res;
             std::vector<char> was_reset;
             {
               py::gil_scoped_release release;
               interruptible scope;  // Ctrl-C: step refuses until reset (vec_env.hpp)
               v.step(actions, obs, res, was_reset);
             }
             const int n = v.size();
             Eigen::VectorXd reward(n), progress(n), lateral(n);
             Eigen::Array<bool, Eigen::Dynamic, 1> term(n), trunc(n), div(n), reset(n);
             for (int i = 0; i < n; ++i) {
               reward[i] = res[i].reward.reward;
               progress[i] = res[i].reward.progress;
               lateral[i] = res[i].reward.lateral;
               term[i] = res[i].terminated;
               trunc[i] = res[i].truncated;
               div[i] = res[i].diverged;
               reset[i] = was_reset[i] != 0;
             }
             py::dict info;
             info["progress"] = progress;
             info["lateral_deviation"] = lateral;
             info["diverged"] = div;
             info["reset"] = reset;
             return py::make_tuple(obs, reward, term, trunc, info);
           },
           "actions"_a,
           "One policy step of all envs (num_envs x 3): (obs, reward, terminated, truncated, info).")
      .def("env", guarded("VecRoverEnv.env", &VecRoverEnv::env), "i"_a,
           py::return_value_policy::reference_internal)
      .def_property_readonly("size", &VecRoverEnv::size)
      .def_property_readonly("threads", &VecRoverEnv::threads);
}

}  // namespace ernest::bindings
