// Python bindings of cpp/walker_sim: the walker in ODE, swing execution and the sag-compensation
// scenario (seed 003 §4.1, §5.1). Argument names equal the C++ names; poses are 4 × 4 matrices.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>

#include "bindings.hpp"
#include "ernest/common/validation.hpp"
#include "interrupt.hpp"
#include "exclusive.hpp"
#include "ernest/walker_sim/footfall_cycle.hpp"
#include "ernest/walker_sim/gait_execution.hpp"
#include "ernest/walker_sim/rock_map.hpp"
#include "ernest/walker_sim/sag_compensation.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::walker_sim;

namespace {
Eigen::Matrix4d mat(const Eigen::Isometry3d& t) { return t.matrix(); }
std::vector<Eigen::Matrix4d> mats(const std::vector<Eigen::Isometry3d>& ts) {
  std::vector<Eigen::Matrix4d> out;
  for (const auto& t : ts) out.push_back(t.matrix());
  return out;
}
}  // namespace

void bind_walker_sim(py::module_& m) {
  py::register_exception<WalkerSimDiverged>(m, "WalkerSimDiverged", PyExc_RuntimeError);

  py::class_<Rock>(m, "Rock", "A box rock on the ground plane, yawed about the vertical.")
      .def(py::init<>())
      .def_readwrite("centre", &Rock::centre, "world [m]")
      .def_readwrite("half_extents", &Rock::half_extents, "[m]")
      .def_readwrite("yaw", &Rock::yaw, "[rad]")
      .def("validate", &Rock::validate, "Raise ValueError naming the first invalid field.");

  py::class_<WalkerSimOptions>(m, "WalkerSimOptions",
                               "ODE walker: step, wheel springs (seed 003 eq 3 via contact ERP/CFM), "
                               "joint position control through hinge motors.")
      .def(py::init<>())
      .def_readwrite("dt", &WalkerSimOptions::dt, "[s]")
      .def_readwrite("contact_stiffness", &WalkerSimOptions::contact_stiffness, "k_zz per wheel [N/m]")
      .def_readwrite("contact_damping", &WalkerSimOptions::contact_damping, "[N s/m]")
      .def_readwrite("friction", &WalkerSimOptions::friction, "Coulomb coefficient")
      .def_readwrite("rock_stiffness", &WalkerSimOptions::rock_stiffness, "[N/m]")
      .def_readwrite("rock_damping", &WalkerSimOptions::rock_damping, "[N s/m]")
      .def_readwrite("position_gain", &WalkerSimOptions::position_gain, "[1/s]")
      .def_readwrite("max_joint_rate", &WalkerSimOptions::max_joint_rate, "[rad/s]")
      .def_readwrite("torque_scale", &WalkerSimOptions::torque_scale, "motor limit / torque limit")
      .def_readwrite("min_link_mass", &WalkerSimOptions::min_link_mass, "[kg]")
      .def("validate", &WalkerSimOptions::validate, "Raise ValueError naming the first invalid field.");

  py::class_<WalkerSim>(m, "WalkerSim",
                        "The walker in ODE over flat ground with box rocks. One thread at a time (a second "
                        "gets RuntimeError).")
      .def(py::init([](const walker::WalkerModel& model, const Eigen::Matrix4d& body, const Eigen::MatrixXd& q,
                       const std::vector<Rock>& rocks, const WalkerSimOptions& options) {
             return std::make_unique<WalkerSim>(model, to_isometry(body, "body"), q, rocks, options);
           }),
           "model"_a, "body"_a, "q"_a, "rocks"_a = std::vector<Rock>{}, "options"_a = WalkerSimOptions{},
           py::keep_alive<1, 2>(), "Build the robot at body pose `body` and configuration q (joints × legs).")
      .def_property_readonly("options", &WalkerSim::options)
      .def_property_readonly("rocks", &WalkerSim::rocks)
      .def_property_readonly("time", guarded("WalkerSim.time", &WalkerSim::time), "[s]")
      .def("step", guarded("WalkerSim.step", &WalkerSim::step), "q_target"_a, "rate"_a = Eigen::MatrixXd(),
           py::call_guard<py::gil_scoped_release, interruptible>(),
           "One physics step towards q_target with feed-forward joint rates; raises WalkerSimDiverged.")
      .def("hold", guarded("WalkerSim.hold", &WalkerSim::hold), "q_target"_a, "seconds"_a, py::call_guard<py::gil_scoped_release, interruptible>(),
           "Hold the targets for `seconds`.")
      .def("body_pose",
           [](const WalkerSim& s) {
             const Busy busy("WalkerSim.body_pose", {&s});
             return mat(s.body_pose());
           }, "Chassis frame, 4 × 4.")
      .def("joint_angles", guarded("WalkerSim.joint_angles", &WalkerSim::joint_angles), "Measured joints × legs [rad].")
      .def("wheel_centres", guarded("WalkerSim.wheel_centres", &WalkerSim::wheel_centres), "3 × legs [m].")
      .def("wheel_axles", guarded("WalkerSim.wheel_axles", &WalkerSim::wheel_axles), "3 × legs.")
      .def("wheel_loads", guarded("WalkerSim.wheel_loads", &WalkerSim::wheel_loads), "Normal force of each wheel's spring [N].")
      .def("rock_clearance", guarded("WalkerSim.rock_clearance", &WalkerSim::rock_clearance), "leg"_a, "Wheel to nearest rock [m] (< 0 overlap; inf without rocks).")
      .def("ground_clearance", guarded("WalkerSim.ground_clearance", &WalkerSim::ground_clearance), "leg"_a, "Wheel's lowest point over z = 0 [m].");

  m.def("wheel_rock_clearance", &wheel_rock_clearance, "centre"_a, "axle"_a, "radius"_a, "width"_a, "rock"_a,
        "Signed distance of a cylindrical wheel to a box rock [m] (FCL).");
  m.def(
      "swing_path",
      [](const walker::WalkerModel& model, const Eigen::Matrix4d& body, int leg, const Eigen::VectorXd& q_start,
         const Eigen::Vector3d& goal, double lift_height) {
        return swing_path(model, to_isometry(body, "body"), leg, q_start, goal, lift_height);
      },
      "model"_a, "body"_a, "leg"_a, "q_start"_a, "goal"_a, "lift_height"_a,
      "Joint waypoints: start, above start, above goal, goal (IK with the body at `body`).");
  m.def(
      "planned_clearance",
      [](const walker::WalkerModel& model, const Eigen::Matrix4d& body, int leg,
         const std::vector<Eigen::VectorXd>& path, const std::vector<Rock>& rocks, int samples) {
        return planned_clearance(model, to_isometry(body, "body"), leg, path, rocks, samples);
      },
      "model"_a, "body"_a, "leg"_a, "path"_a, "rocks"_a, "samples"_a = 40,
      "Smallest wheel-to-rock clearance along the joint path with the body held at `body` [m].");

  py::class_<ExecutionOptions>(m, "ExecutionOptions", "Joint-path execution: speed and pauses.")
      .def(py::init<>())
      .def_readwrite("joint_speed", &ExecutionOptions::joint_speed, "[rad/s]")
      .def_readwrite("pause", &ExecutionOptions::pause, "hold at each waypoint [s]")
      .def_property(
          "frame_interval", [](const ExecutionOptions& o) { return o.frame_interval; },
          [](ExecutionOptions& o, std::optional<double> dt) {
            if (dt) {
              ernest::require_in_range("ExecutionOptions", "frame_interval", *dt, 0.0, 60.0);
              ernest::require_positive("ExecutionOptions", "frame_interval", *dt);
            }
            o.frame_interval = dt;
          },
          "animation frames every [s], (0, 60]; None (default): no frames")
      .def("validate", &ExecutionOptions::validate, "Raise ValueError naming the first invalid field.");

  py::class_<ExecutionTrace>(m, "ExecutionTrace", "What the swing wheel did in the simulator.")
      .def_readonly("time", &ExecutionTrace::time, "[s]")
      .def_readonly("rock_clearance", &ExecutionTrace::rock_clearance, "[m]")
      .def_readonly("ground_clearance", &ExecutionTrace::ground_clearance, "[m]")
      .def_readonly("body_height", &ExecutionTrace::body_height, "[m]")
      .def_readonly("phase", &ExecutionTrace::phase, "segment index, -1 in the first pause")
      .def_readonly("min_rock_clearance", &ExecutionTrace::min_rock_clearance, "[m] (< 0: hit)")
      .def_readonly("min_ground_clearance", &ExecutionTrace::min_ground_clearance, "during the transfer [m]")
      .def_readonly("min_any_rock_clearance", &ExecutionTrace::min_any_rock_clearance, "every wheel [m]")
      .def_readonly("wheel_path", &ExecutionTrace::wheel_path, "traced wheel centre, 3 × steps [m]")
      .def_property_readonly("waypoint_body", [](const ExecutionTrace& t) { return mats(t.waypoint_body); },
                             "body pose after each waypoint's pause (4 × 4)")
      .def_readonly("frame_time", &ExecutionTrace::frame_time, "[s]")
      .def_property_readonly("frame_body", [](const ExecutionTrace& t) { return mats(t.frame_body); }, "4 × 4 each")
      .def_readonly("frame_q", &ExecutionTrace::frame_q, "joints × legs each")
      .def_readonly("final_q", &ExecutionTrace::final_q)
      .def_readonly("simulated_seconds", &ExecutionTrace::simulated_seconds)
      .def_readonly("wall_seconds", &ExecutionTrace::wall_seconds);
  m.def("execute_joint_path", guarded("execute_joint_path", &execute_joint_path), "sim"_a, "leg"_a, "stance"_a, "path"_a,
        "options"_a = ExecutionOptions{}, py::call_guard<py::gil_scoped_release, interruptible>(),
        "Execute a joint path of `leg` (other legs held at `stance`) and trace its clearances.");

  m.def("execute_configuration_path", guarded("execute_configuration_path", &execute_configuration_path), "sim"_a, "leg"_a, "path"_a,
        "options"_a = ExecutionOptions{}, py::call_guard<py::gil_scoped_release, interruptible>(),
        "Execute whole-robot configurations (every leg at once); trace wheel `leg` (None: none).");

  py::class_<GaitExecution>(m, "GaitExecution", "One executed gait cycle.")
      .def_readonly("steps", &GaitExecution::steps)
      .def_readonly("shifts", &GaitExecution::shifts)
      .def_readonly("min_ground_clearance", &GaitExecution::min_ground_clearance, "swing wheels [m]")
      .def_readonly("body_start", &GaitExecution::body_start, "[m]")
      .def_readonly("body_end", &GaitExecution::body_end, "[m]")
      .def_readonly("planned_advance", &GaitExecution::planned_advance, "[m]")
      .def_readonly("simulated_seconds", &GaitExecution::simulated_seconds)
      .def_readonly("wall_seconds", &GaitExecution::wall_seconds);
  m.def("execute_gait_cycle", guarded("execute_gait_cycle", &execute_gait_cycle), "sim"_a, "plan"_a, "cycle"_a, "options"_a = ExecutionOptions{},
        py::call_guard<py::gil_scoped_release, interruptible>(),
        "Execute cycle `cycle` of a walker.GaitPlan (steps through the compliance waypoints, shifts).");

  py::class_<SagScenarioOptions>(m, "SagScenarioOptions", "Seed 003 §4.1 rigid vs sag-compensated swing.")
      .def(py::init<>())
      .def_readwrite("leg", &SagScenarioOptions::leg)
      .def_readwrite("step", &SagScenarioOptions::step, "wheel step in the body frame [m]")
      .def_readwrite("rock_half_extents", &SagScenarioOptions::rock_half_extents, "[m]")
      .def_readwrite("planned_clearance", &SagScenarioOptions::planned_clearance, "on paper [m]")
      .def_readwrite("min_lift", &SagScenarioOptions::min_lift, "[m]")
      .def_readwrite("lift_resolution", &SagScenarioOptions::lift_resolution, "[m]")
      .def_readwrite("tangential_ratio", &SagScenarioOptions::tangential_ratio, "k_xx / k_zz of the sag model")
      .def_readwrite("settle_time", &SagScenarioOptions::settle_time, "[s]")
      .def_readwrite("sim", &SagScenarioOptions::sim)
      .def_readwrite("execution", &SagScenarioOptions::execution)
      .def("validate", &SagScenarioOptions::validate, "Raise ValueError naming the first invalid field.");

  py::class_<SwingPlan>(m, "SwingPlan", "A swing plan and the body pose it assumes.")
      .def_property_readonly("assumed_body", [](const SwingPlan& p) { return mat(p.assumed_body); })
      .def_readonly("path", &SwingPlan::path)
      .def_readonly("lift_height", &SwingPlan::lift_height, "[m]")
      .def_readonly("planned_clearance", &SwingPlan::planned_clearance, "[m]");

  py::class_<SagScenarioResult>(m, "SagScenarioResult", "Rigid and compensated plans, their runs, sag check.")
      .def_readonly("rocks", &SagScenarioResult::rocks)
      .def_readonly("start", &SagScenarioResult::start)
      .def_readonly("goal", &SagScenarioResult::goal)
      .def_readonly("rigid", &SagScenarioResult::rigid)
      .def_readonly("compensated", &SagScenarioResult::compensated)
      .def_readonly("rigid_run", &SagScenarioResult::rigid_run)
      .def_readonly("compensated_run", &SagScenarioResult::compensated_run)
      .def_readonly("rigid_corners", &SagScenarioResult::rigid_corners, "hip-mount heights, no sag [m]")
      .def_readonly("predicted_six_corners", &SagScenarioResult::predicted_six_corners, "[m]")
      .def_readonly("measured_six_corners", &SagScenarioResult::measured_six_corners, "[m]")
      .def_readonly("predicted_lifted_corners", &SagScenarioResult::predicted_lifted_corners, "[m]")
      .def_readonly("measured_lifted_corners", &SagScenarioResult::measured_lifted_corners, "[m]")
      .def_readonly("six_error", &SagScenarioResult::six_error, "[m]")
      .def_readonly("lifted_error", &SagScenarioResult::lifted_error, "[m]");
  m.def("run_sag_scenario", &run_sag_scenario, "model"_a, "options"_a = SagScenarioOptions{},
        py::call_guard<py::gil_scoped_release, interruptible>(),
        "Plan a swing over a rock against the rigid and the sagged pose, execute both in ODE.");

  py::class_<RockMapOptions>(m, "RockMapOptions", "Grid of rock_height_map: square, spacing, dilation.")
      .def(py::init<>())
      .def_readwrite("length", &RockMapOptions::length, "[m]")
      .def_readwrite("centre_x", &RockMapOptions::centre_x, "[m]")
      .def_readwrite("centre_y", &RockMapOptions::centre_y, "[m]")
      .def_readwrite("spacing", &RockMapOptions::spacing, "[m]")
      .def_readwrite("dilation", &RockMapOptions::dilation, "footprints grown by [m]")
      .def("validate", &RockMapOptions::validate, "Raise ValueError naming the first invalid field.");
  m.def("box_rock_field", &box_rock_field, "options"_a, "keep_clear"_a,
        "Box rocks placed like footfall.rock_field's bumps (footfall.RockFieldOptions).");
  m.def("rock_height_map", &rock_height_map, "rocks"_a, "options"_a = RockMapOptions{},
        "The rocks rasterised into the planner's HeightMap: box top inside a footprint, 0 outside.");

  py::class_<FootfallCycleOptions>(m, "FootfallCycleOptions", "A planned and executed FootFall gait cycle.")
      .def(py::init<>())
      .def_readwrite("stride", &FootfallCycleOptions::stride, "foot step = body advance per cycle [m]")
      .def_readwrite("heading", &FootfallCycleOptions::heading, "[rad]")
      .def_readwrite("foothold_radius", &FootfallCycleOptions::foothold_radius, "rock-free radius [m]")
      .def_readwrite("flat_tolerance", &FootfallCycleOptions::flat_tolerance, "[m]")
      .def_readwrite("max_candidates", &FootfallCycleOptions::max_candidates, "footholds tried per step")
      .def_readwrite("candidate_spacing", &FootfallCycleOptions::candidate_spacing, "between candidates [m]")
      .def_readwrite("settle_time", &FootfallCycleOptions::settle_time, "[s]")
      .def_readwrite("torque_preference", &FootfallCycleOptions::torque_preference,
                     "candidates by distance + this x peak torque fraction [m], [0, 100] (§7.1)")
      .def_readwrite("execute", &FootfallCycleOptions::execute, "False: plan only (no simulator)")
      .def_property(
          "steps", [](const FootfallCycleOptions& o) { return o.steps; },
          [](FootfallCycleOptions& o, std::optional<int> n) {
            if (n) ernest::require_in_range("FootfallCycleOptions", "steps", *n, 1, 1000);
            o.steps = n;
          },
          "first steps of the cycle to take, [1, legs]; None (default): one per leg")
      .def_readwrite("step", &FootfallCycleOptions::step, "footfall.StepOptions")
      .def_readwrite("sim", &FootfallCycleOptions::sim)
      .def_readwrite("execution", &FootfallCycleOptions::execution)
      .def("validate", &FootfallCycleOptions::validate, "joints"_a, "Raise ValueError naming the first invalid field.");
  py::class_<FootfallStepRecord>(m, "FootfallStepRecord", "One step of the cycle: map, plan, execution.")
      .def_readonly("leg", &FootfallStepRecord::leg)
      .def_readonly("map", &FootfallStepRecord::map, "footfall.StabilityMap before the step")
      .def_readonly("map_seconds", &FootfallStepRecord::map_seconds)
      .def_readonly("nominal_goal", &FootfallStepRecord::nominal_goal, "[m]")
      .def_readonly("candidates_tried", &FootfallStepRecord::candidates_tried)
      .def_readonly("plan", &FootfallStepRecord::plan, "footfall.StepPlan")
      .def_readonly("planned_wheel", &FootfallStepRecord::planned_wheel, "3 × n, assumed pose [m]")
      .def_readonly("executed_wheel", &FootfallStepRecord::executed_wheel, "3 × n, simulator [m]")
      .def_readonly("planned_clearance", &FootfallStepRecord::planned_clearance, "on paper [m]")
      .def_readonly("swing_rock_clearance", &FootfallStepRecord::swing_rock_clearance, "executed [m]")
      .def_readonly("min_rock_clearance", &FootfallStepRecord::min_rock_clearance, "every wheel [m]")
      .def_readonly("transfer_ground_clearance", &FootfallStepRecord::transfer_ground_clearance, "[m]")
      .def_readonly("body_before", &FootfallStepRecord::body_before, "planned [m]")
      .def_readonly("body_after", &FootfallStepRecord::body_after, "planned [m]");
  py::class_<FootfallCycleResult>(m, "FootfallCycleResult", "The planned and executed cycle.")
      .def_readonly("completed", &FootfallCycleResult::completed)
      .def_readonly("reason", &FootfallCycleResult::reason)
      .def_readonly("steps", &FootfallCycleResult::steps)
      .def_readonly("body_start", &FootfallCycleResult::body_start, "measured [m]")
      .def_readonly("body_end", &FootfallCycleResult::body_end, "measured [m]")
      .def_readonly("planned_advance", &FootfallCycleResult::planned_advance, "[m]")
      .def_readonly("min_rock_clearance", &FootfallCycleResult::min_rock_clearance, "[m]")
      .def_readonly("frame_time", &FootfallCycleResult::frame_time, "[s]")
      .def_property_readonly("frame_body", [](const FootfallCycleResult& r) { return mats(r.frame_body); })
      .def_readonly("frame_q", &FootfallCycleResult::frame_q, "joints × legs each")
      .def_readonly("planning_seconds", &FootfallCycleResult::planning_seconds)
      .def_readonly("simulated_seconds", &FootfallCycleResult::simulated_seconds)
      .def_readonly("simulation_wall_seconds", &FootfallCycleResult::simulation_wall_seconds);
  m.def("run_footfall_cycle", &run_footfall_cycle, "model"_a, "terrain"_a, "rocks"_a,
        "options"_a = FootfallCycleOptions{}, py::call_guard<py::gil_scoped_release, interruptible>(),
        "Plan (on `terrain`) and execute (among `rocks`) one reverse-wave gait cycle from the standard stance.");
}

}  // namespace ernest::bindings
