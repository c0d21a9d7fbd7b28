// Python bindings of cpp/sensing. Argument names equal the C++ names.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "exclusive.hpp"
#include "ernest/sensing/elevation_sampler.hpp"
#include "ernest/sensing/fts_processor.hpp"
#include "ernest/sensing/observation.hpp"
#include "ernest/sensing/path_reward.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::sensing;

namespace {
// Lets Python subclasses of HeightSource serve heights: height(x, y) returns a float or None.
class PyHeightSource : public HeightSource {
 public:
  bool height(double x, double y, double& z) const override {
    py::gil_scoped_acquire gil;
    py::function f = py::get_override(static_cast<const HeightSource*>(this), "height");
    if (!f) throw std::runtime_error("HeightSource.height(x, y) is not implemented");
    py::object r = f(x, y);
    if (r.is_none()) return false;
    z = r.cast<double>();
    return std::isfinite(z);
  }
};
}  // namespace

void bind_sensing(py::module_& m) {
  m.attr("OBSERVATION_SIZE") = kObservationSize;
  m.attr("ACTION_SIZE") = kActionSize;
  m.attr("OBSERVATION_LAYOUT_VERSION") = kObservationLayoutVersion;
  m.attr("ELEVATION_SAMPLES") = kElevationSamples;
  m.attr("OBSERVATION_CLIP") = kObservationClip;
  py::dict index;
  index["heading_deviation"] = static_cast<int>(kHeadingDeviation);
  index["lateral_deviation"] = static_cast<int>(kLateralDeviation);
  index["roll"] = static_cast<int>(kRoll);
  index["pitch"] = static_cast<int>(kPitch);
  index["gimbal_yaw"] = static_cast<int>(kGimbalYaw);
  index["gimbal_roll"] = static_cast<int>(kGimbalRoll);
  index["fts"] = static_cast<int>(kFtsBegin);
  index["elevation"] = static_cast<int>(kElevationBegin);
  index["action"] = static_cast<int>(kActionBegin);
  m.attr("OBSERVATION_INDEX") = index;

  py::class_<FtsFilterOptions>(m, "FtsFilterOptions", "Force–torque low-pass settings (§4.2).")
      .def(py::init<>())
      .def_readwrite("sample_rate", &FtsFilterOptions::sample_rate, "[Hz]")
      .def_readwrite("cutoff", &FtsFilterOptions::cutoff, "[Hz]")
      .def("validate", &FtsFilterOptions::validate, "Raise ValueError on an invalid field.");

  py::class_<FtsProcessor>(m, "FtsProcessor",
                           "Low-pass, bias and four-sensor-mean removal of the 4 x 6 wrenches.")
      .def(py::init<const FtsFilterOptions&>(), "options"_a = FtsFilterOptions{})
      .def("reset", &FtsProcessor::reset, "initial"_a, "Start the filter at these wrenches.")
      .def("update", &FtsProcessor::update, "raw"_a, "One sensor sample (4 x 6).")
      .def("set_bias", &FtsProcessor::set_bias, "bias"_a, "Calibration biases (4 x 6).")
      .def_property_readonly("filtered", &FtsProcessor::filtered, "Low-passed wrenches (4 x 6).")
      .def_property_readonly("bias", &FtsProcessor::bias)
      .def("processed", &FtsProcessor::processed, "filtered - bias - four-sensor mean (4 x 6).")
      .def_property_readonly("alpha", &FtsProcessor::alpha, "Filter gain per sample.");

  py::class_<HeightSource, PyHeightSource>(m, "HeightSource",
                                           "Subclass and define height(x, y) -> float or None.")
      .def(py::init<>());
  py::class_<GridHeightSource, HeightSource>(m, "GridHeightSource",
                                             "Height grid with NaN holes (elevation map).")
      .def(py::init<Eigen::MatrixXd, double, double, double>(), "heights"_a, "spacing"_a,
           "origin_x"_a, "origin_y"_a)
      .def("height",
           [](const GridHeightSource& g, double x, double y) -> py::object {
             double z;
             return g.height(x, y, z) ? py::object(py::float_(z)) : py::object(py::none());
           },
           "x"_a, "y"_a, "Height at (x, y), or None in a hole.")
      .def_property_readonly("heights", &GridHeightSource::heights);

  py::class_<ElevationSamplingOptions>(m, "ElevationSamplingOptions",
                                       "Geometry of the 12 elevation samples (§4.2, Fig. 11).")
      .def(py::init<>())
      .def_readwrite("wheel_xy", &ElevationSamplingOptions::wheel_xy,
                     "4 x 2 wheel contact points (FL, FR, RL, RR) in the chassis frame [m]")
      .def_readwrite("ground_z", &ElevationSamplingOptions::ground_z, "[m]")
      .def_readwrite("first_offset", &ElevationSamplingOptions::first_offset, "[m]")
      .def_readwrite("spacing", &ElevationSamplingOptions::spacing, "[m]")
      .def_readwrite("points_per_wheel", &ElevationSamplingOptions::points_per_wheel)
      .def_readwrite("search_step", &ElevationSamplingOptions::search_step, "[m]")
      .def_readwrite("search_range", &ElevationSamplingOptions::search_range, "[m]")
      .def("validate", &ElevationSamplingOptions::validate, "Raise ValueError on an invalid field.");

  py::class_<ElevationSampler>(m, "ElevationSampler", "Samples 12 chassis-relative elevations.")
      .def(py::init<const ElevationSamplingOptions&>(), "options"_a = ElevationSamplingOptions{})
      .def("sample",
           [](const ElevationSampler& s, const Eigen::Vector3d& position,
              const Eigen::Matrix3d& rotation, const HeightSource& source) {
             // the source may be an ElevationMap another thread is fusing into (exclusive.hpp)
             const Busy busy("ElevationSampler.sample", {dynamic_cast<const void*>(&source)});
             const ElevationSample e = s.sample(position, rotation, source);
             return py::make_tuple(Eigen::VectorXd(e.values),
                                   std::vector<int>(e.source.begin(), e.source.end()));
           },
           "position"_a, "rotation"_a, "source"_a,
           "(values[12], source[12]): source 0 measured, 1 interpolated, 2 held, 3 unknown.")
      .def("point", &ElevationSampler::point, "k"_a, "Chassis-frame (x, y) of sample k.")
      .def_property_readonly("options", &ElevationSampler::options);

  m.def("fill_line",
        [](const Eigen::VectorXd& s, Eigen::VectorXd values,
           const Eigen::Array<bool, Eigen::Dynamic, 1>& valid) {
          const bool any = fill_line(s, values, valid);
          return py::make_tuple(values, any);
        },
        "s"_a, "values"_a, "valid"_a,
        "Fill missing values along a line: returns (filled values, any_valid).");

  py::class_<ObservationScales>(m, "ObservationScales", "Maximum expected values (normalisers).")
      .def(py::init<>())
      .def_readwrite("heading", &ObservationScales::heading)
      .def_readwrite("lateral", &ObservationScales::lateral)
      .def_readwrite("attitude", &ObservationScales::attitude)
      .def_readwrite("gimbal_yaw", &ObservationScales::gimbal_yaw)
      .def_readwrite("gimbal_roll", &ObservationScales::gimbal_roll)
      .def_readwrite("force", &ObservationScales::force)
      .def_readwrite("torque", &ObservationScales::torque)
      .def_readwrite("elevation", &ObservationScales::elevation)
      .def_readwrite("action", &ObservationScales::action)
      .def("validate", &ObservationScales::validate, "Raise ValueError on an invalid field.")
      .def("divisors", &ObservationScales::divisors, "The 45 divisors in observation order.");

  py::class_<ObservationInputs>(m, "ObservationInputs", "Physical inputs of one observation (SI).")
      .def(py::init<>())
      .def_readwrite("heading_deviation", &ObservationInputs::heading_deviation)
      .def_readwrite("lateral_deviation", &ObservationInputs::lateral_deviation)
      .def_readwrite("roll", &ObservationInputs::roll)
      .def_readwrite("pitch", &ObservationInputs::pitch)
      .def_readwrite("gimbal_yaw", &ObservationInputs::gimbal_yaw)
      .def_readwrite("gimbal_roll", &ObservationInputs::gimbal_roll)
      .def_readwrite("fts", &ObservationInputs::fts, "processed wrenches (4 x 6)")
      .def_readwrite("elevation", &ObservationInputs::elevation, "12 samples [m]")
      .def_readwrite("action", &ObservationInputs::action, "current action in [-1, 1]");
  m.def("build_observation", &build_observation, "inputs"_a, "scales"_a = ObservationScales{},
        "The 45-value observation of §4.2 (inputs / scales).");
  m.def("observation_names", &observation_names, "Names of the 45 observation entries.");

  py::class_<ActionLimits>(m, "ActionLimits", "Action limits of §4.2 (SI units).")
      .def(py::init<>())
      .def_readwrite("vx_max", &ActionLimits::vx_max, "[m/s]")
      .def_readwrite("yaw_rate_max", &ActionLimits::yaw_rate_max, "[rad/s]")
      .def_readwrite("roll_rate_max", &ActionLimits::roll_rate_max, "[rad/s]")
      .def("validate", &ActionLimits::validate, "Raise ValueError on an invalid field.");
  m.def("action_to_command", &action_to_command, "action"_a, "limits"_a = ActionLimits{},
        "(Vx, yaw rate, roll rate) from a normalised action in [-1, 1]^3.");
  m.def("command_to_action", &command_to_action, "command"_a, "limits"_a = ActionLimits{},
        "Normalised action from (Vx, yaw rate, roll rate).");

  py::class_<PathLine>(m, "PathLine", "Straight desired path (eqs 33–37).")
      .def(py::init<>())
      .def(py::init([](double x0, double y0, double heading) { return PathLine{x0, y0, heading}; }),
           "x0"_a, "y0"_a, "heading"_a)
      .def_readwrite("x0", &PathLine::x0)
      .def_readwrite("y0", &PathLine::y0)
      .def_readwrite("heading", &PathLine::heading)
      .def("progress", &PathLine::progress, "x_prev"_a, "y_prev"_a, "x"_a, "y"_a, "eq 36")
      .def("lateral_deviation", &PathLine::lateral_deviation, "x"_a, "y"_a, "eq 37")
      .def("heading_deviation", &PathLine::heading_deviation, "yaw"_a, "wrapped to (-pi, pi]")
      .def("arc_length", &PathLine::arc_length, "x"_a, "y"_a, "distance along the path");

  py::class_<RewardWeights>(m, "RewardWeights", "Weights of eq 38.")
      .def(py::init<>())
      .def_readwrite("w_s", &RewardWeights::w_s)
      .def_readwrite("w_delta", &RewardWeights::w_delta)
      .def_readwrite("w_tau", &RewardWeights::w_tau)
      .def_readwrite("dt", &RewardWeights::dt)
      .def("validate", &RewardWeights::validate, "Raise ValueError on an invalid field.");
  py::class_<RewardTerms>(m, "RewardTerms", "The terms of eq 38.")
      .def_readonly("progress", &RewardTerms::progress)
      .def_readonly("lateral", &RewardTerms::lateral)
      .def_readonly("progress_term", &RewardTerms::progress_term)
      .def_readonly("lateral_term", &RewardTerms::lateral_term)
      .def_readonly("torque_term", &RewardTerms::torque_term)
      .def_readonly("reward", &RewardTerms::reward);
  m.def("compute_reward", &compute_reward, "path"_a, "x_prev"_a, "y_prev"_a, "x"_a, "y"_a,
        "roll_torque"_a, "weights"_a = RewardWeights{}, "Reward of eq 38 with its terms.");
}

}  // namespace ernest::bindings
