// Python bindings of cpp/footfall (seed 003 §3.3–3.4, §4.1, §5.1: FootFall's single-leg
// planning). Argument names equal the C++ names; poses are 4 × 4 homogeneous matrices; whole-robot
// configurations are (joints per leg, legs) arrays, paths (joints, waypoints) arrays; the terrain
// is a dynamics.HeightMap.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <stdexcept>
#include <string>

#include "bindings.hpp"
#include "ernest/common/validation.hpp"
#include "interrupt.hpp"
#include "exclusive.hpp"
#include "ernest/footfall/leg_collision.hpp"
#include "ernest/footfall/leg_planner.hpp"
#include "ernest/footfall/path_smoothing.hpp"
#include "ernest/footfall/scenario.hpp"
#include "ernest/footfall/stability_map.hpp"
#include "ernest/footfall/step_planner.hpp"
#include "ernest/footfall/swing_sag.hpp"
#include "ernest/footfall/stance_torque.hpp"
#include "ernest/footfall/torque_smoothing.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::footfall;
using dynamics::HeightMap;
using walker::WalkerModel;

namespace {

Eigen::Isometry3d body_pose(const Eigen::Matrix4d& t) { return to_isometry(t, "body"); }

Eigen::Matrix4d matrix(const Eigen::Isometry3d& t) { return t.matrix(); }

}  // namespace

void bind_footfall(py::module_& m) {
  py::enum_<StabilityCriterion>(m, "StabilityCriterion", "SSM or NESM of the CPS; Auto: NESM on slopes.")
      .value("Auto", StabilityCriterion::kAuto)
      .value("SSM", StabilityCriterion::kSsm)
      .value("NESM", StabilityCriterion::kNesm);
  py::enum_<CellStatus>(m, "CellStatus",
                        "Map cell: unreachable (0), unstable (1), stable (2) or overloaded (3: reachable and "
                        "stable, but a joint's static torque exceeds StabilityMapOptions.max_saturation, §7.1).")
      .value("Unreachable", CellStatus::kUnreachable)
      .value("Unstable", CellStatus::kUnstable)
      .value("Stable", CellStatus::kStable)
      .value("Overloaded", CellStatus::kOverloaded);
  py::enum_<PlannerType>(m, "PlannerType", "OMPL planner: SBL (FootFall's) or RRT-Connect (reference).")
      .value("SBL", PlannerType::kSbl)
      .value("RRTConnect", PlannerType::kRrtConnect);
  py::enum_<PlanStatus>(m, "PlanStatus", "Solved, or NoPlan with a reason.")
      .value("Solved", PlanStatus::kSolved)
      .value("NoPlan", PlanStatus::kNoPlan);

  py::class_<CollisionOptions>(m, "CollisionOptions", "Clearances of the swing leg's checks [m] (§3.4.1).")
      .def(py::init<>())
      .def_readwrite("environment_clearance", &CollisionOptions::environment_clearance, "terrain [m]")
      .def_readwrite("own_leg_clearance", &CollisionOptions::own_leg_clearance, "within the swing leg [m]")
      .def_readwrite("clearance_table", &CollisionOptions::clearance_table,
                     "(n+1, n+2) swing shape x other leg's shape / chassis [m]; empty = default")
      .def_readwrite("terrain_margin", &CollisionOptions::terrain_margin, "mesh beyond the reach [m]")
      .def("validate", &CollisionOptions::validate, "joints"_a, "Raise ValueError naming the field.");
  m.def("default_clearance_table", &default_clearance_table, "joints"_a,
        "Default per-pair clearances: 0.05 m between legs, 0.03 m to the chassis.");

  py::class_<StabilityMapOptions>(m, "StabilityMapOptions", "Stability map options (§3.3).")
      .def(py::init<>())
      .def_readwrite("cell", &StabilityMapOptions::cell, "[m]")
      .def_readwrite("lift_height", &StabilityMapOptions::lift_height, "compliance waypoints [m]")
      .def_readwrite("min_margin", &StabilityMapOptions::min_margin, "stable above this [m]")
      .def_readwrite("criterion", &StabilityMapOptions::criterion)
      .def_readwrite("slope_threshold", &StabilityMapOptions::slope_threshold, "[rad] for Auto")
      .def_readwrite("ik_evaluations", &StabilityMapOptions::ik_evaluations)
      .def_readwrite("torques", &StabilityMapOptions::torques,
                     "evaluate each reachable cell's peak joint torque (after the step, and during it with the "
                     "leg at the waypoint above the cell; §7.1)")
      .def_readwrite("max_saturation", &StabilityMapOptions::max_saturation,
                     "stable cells whose peak |tau| / limit exceeds this are Overloaded, [0, inf]; inf: never")
      .def("validate", &StabilityMapOptions::validate, "Raise ValueError naming the field.");

  py::class_<StabilityMap>(m, "StabilityMap", "Cell (i, j) at (origin_x + i cell, origin_y + j cell).")
      .def_readonly("origin_x", &StabilityMap::origin_x)
      .def_readonly("origin_y", &StabilityMap::origin_y)
      .def_readonly("cell", &StabilityMap::cell)
      .def_readonly("status", &StabilityMap::status, "uint8 CellStatus values")
      .def_readonly("margin", &StabilityMap::margin, "[m], NaN where unreachable")
      .def_readonly("nesm", &StabilityMap::nesm)
      .def_readonly("start_waypoint_reachable", &StabilityMap::start_waypoint_reachable)
      .def_readonly("hip", &StabilityMap::hip)
      .def_readonly("reach", &StabilityMap::reach)
      .def_readonly("ik_solves", &StabilityMap::ik_solves)
      .def_readonly("saturation", &StabilityMap::saturation,
                    "peak |tau| / limit per cell (NaN where unreachable or torques are off)")
      .def_readonly("lift_saturation", &StabilityMap::lift_saturation,
                    "peak |tau| / limit with the leg lifted above its current foot (NaN when torques are off)")
      .def("count", &StabilityMap::count, "status"_a, "Cells with this status.");

  py::class_<CellEvaluation>(m, "CellEvaluation", "One evaluated ground point.")
      .def_readonly("status", &CellEvaluation::status)
      .def_readonly("margin", &CellEvaluation::margin)
      .def_readonly("q", &CellEvaluation::q)
      .def_readonly("q_above", &CellEvaluation::q_above,
                    "at the compliance waypoint above the point; NaN when it was not reached")
      .def_readonly("cg", &CellEvaluation::cg)
      .def_readonly("saturation_down", &CellEvaluation::saturation_down,
                    "peak |tau| / limit after the step (NaN when torques are off or unreachable)")
      .def_readonly("saturation_lifted", &CellEvaluation::saturation_lifted,
                    "peak |tau| / limit with the leg at q_above (NaN when torques are off or "
                    "unreachable)")
      .def_readonly("saturation", &CellEvaluation::saturation, "the larger (NaN when torques are off)")
      .def_readonly("peak_leg", &CellEvaluation::peak_leg)
      .def_readonly("peak_joint", &CellEvaluation::peak_joint);

  py::class_<StabilityMapper>(m, "StabilityMapper",
                              "Foot placements of one leg for a stance over a terrain (§3.3).")
      .def(py::init([](const WalkerModel& model, const HeightMap& terrain, const Eigen::Matrix4d& body,
                       const Eigen::MatrixXd& q, int leg, const StabilityMapOptions& options) {
             return std::make_unique<StabilityMapper>(model, terrain, body_pose(body), q, leg, options);
           }),
           "model"_a, "terrain"_a, "body"_a, "q"_a, "leg"_a, "options"_a = StabilityMapOptions{},
           py::keep_alive<1, 2>(), py::keep_alive<1, 3>())
      .def("map", guarded("StabilityMapper.map", &StabilityMapper::map), py::call_guard<py::gil_scoped_release, interruptible>(),
           "The whole map over the leg's reach.")
      .def("evaluate", guarded("StabilityMapper.evaluate", &StabilityMapper::evaluate), "x"_a, "y"_a, "seed"_a,
           py::call_guard<py::gil_scoped_release, interruptible>(), "One ground point (world x, y).")
      .def_property_readonly("nesm", &StabilityMapper::nesm)
      .def_property_readonly("start_above", guarded("StabilityMapper.start_above", &StabilityMapper::start_above))
      .def_property_readonly("start_waypoint_reachable", &StabilityMapper::start_waypoint_reachable);

  py::class_<LegCollisionChecker>(m, "LegCollisionChecker",
                                  "Self and terrain collisions of one swing leg with FCL (§3.4.1).")
      .def(py::init([](const WalkerModel& model, const HeightMap& terrain, const Eigen::Matrix4d& body,
                       const Eigen::MatrixXd& q, int leg, const CollisionOptions& options) {
             return std::make_unique<LegCollisionChecker>(model, terrain, body_pose(body), q, leg, options);
           }),
           "model"_a, "terrain"_a, "body"_a, "q"_a, "leg"_a, "options"_a = CollisionOptions{},
           py::keep_alive<1, 2>())
      .def("valid", guarded("LegCollisionChecker.valid", &LegCollisionChecker::valid), "q_leg"_a, "include_wheel"_a = true,
           "Limits, self-collisions and the terrain (without the wheel when include_wheel is False).")
      .def("motion_valid", guarded("LegCollisionChecker.motion_valid", &LegCollisionChecker::motion_valid), "a"_a, "b"_a, "epsilon"_a, "include_wheel"_a = true,
           py::call_guard<py::gil_scoped_release, interruptible>(),
           "Straight edge a -> b by recursive bisection to epsilon [rad] (at least 1e-5).")
      .def("checks", &LegCollisionChecker::checks, "Configurations checked so far.");
  m.def("first_colliding_edge",
        [](LegCollisionChecker& checker, const Eigen::Ref<const Eigen::MatrixXd>& path, double resolution,
           int wheel_free_edges) {
          const Busy busy("first_colliding_edge", {&checker});
          return first_colliding_edge(checker, path, resolution, wheel_free_edges);
        },
        "checker"_a, "path"_a, "resolution"_a,
        "wheel_free_edges"_a = 0, py::call_guard<py::gil_scoped_release, interruptible>(),
        "Dense re-check of a path every `resolution` [rad] (at least 1e-5): index of the first "
        "colliding edge, or -1.");

  py::class_<PlannerOptions>(m, "PlannerOptions", "Single-leg planner options (§3.4.1).")
      .def(py::init<>())
      .def_readwrite("planner", &PlannerOptions::planner)
      .def_readwrite("time_limit", &PlannerOptions::time_limit, "[s]")
      .def_readwrite("epsilon", &PlannerOptions::epsilon, "[rad]")
      .def_property(
          "range", [](const PlannerOptions& o) { return o.range; },
          [](PlannerOptions& o, std::optional<double> r) {
            if (r) {
              ernest::require_in_range("PlannerOptions", "range", *r, 0.0, 100.0);
              ernest::require_positive("PlannerOptions", "range", *r);
            }
            o.range = r;
          },
          "longest tree step [rad], (0, 100]; None: OMPL's default (20 % of the joint space's "
          "extent)")
      .def_readwrite("seed", &PlannerOptions::seed)
      .def("validate", &PlannerOptions::validate, "Raise ValueError naming the field.");
  py::class_<PlanResult>(m, "PlanResult", "A plan, or none with the reason.")
      .def_readonly("status", &PlanResult::status)
      .def_readonly("reason", &PlanResult::reason)
      .def_readonly("path", &PlanResult::path, "(joints, waypoints)")
      .def_readonly("seconds", &PlanResult::seconds)
      .def_readonly("length", &PlanResult::length, "[rad]")
      .def_readonly("checks", &PlanResult::checks)
      .def_property_readonly("solved", [](const PlanResult& r) { return r.status == PlanStatus::kSolved; });
  m.def("path_length", &path_length, "path"_a, "Euclidean joint-space length [rad].");
  py::class_<LegPlanner>(m, "LegPlanner", "OMPL SBL (or RRT-Connect) in one leg's joint space.")
      .def(py::init<LegCollisionChecker&, const PlannerOptions&>(), "checker"_a, "options"_a = PlannerOptions{},
           py::keep_alive<1, 2>())
      .def_property_readonly("options", &LegPlanner::options)
      .def("plan",
           [](LegPlanner& p, const Eigen::Ref<const Eigen::VectorXd>& start,
              const Eigen::Ref<const Eigen::VectorXd>& goal) {
             const Busy busy("LegPlanner.plan", {&p, &p.checker()});
             return p.plan(start, goal);
           },
           "start"_a, "goal"_a, py::call_guard<py::gil_scoped_release, interruptible>(),
           "Joint-space query (ValueError for NaN; NoPlan with the reason otherwise).")
      .def("simplify_with_ompl",
           [](LegPlanner& p, const Eigen::Ref<const Eigen::MatrixXd>& path) {
             const Busy busy("LegPlanner.simplify_with_ompl", {&p, &p.checker()});
             return p.simplify_with_ompl(path);
           },
           "path"_a,
           py::call_guard<py::gil_scoped_release, interruptible>(), "OMPL's PathSimplifier.simplifyMax (reference).");

  py::enum_<SmoothingObjective>(m, "SmoothingObjective",
                                "Length: shortest joint-space path (§3.4.2); PeakTorque: smallest peak joint torque "
                                "with the leg in the air, then length (§7.1).")
      .value("Length", SmoothingObjective::kLength)
      .value("PeakTorque", SmoothingObjective::kPeakTorque);
  py::class_<SmoothingOptions>(m, "SmoothingOptions", "Dijkstra–bisection smoothing (§3.4.2).")
      .def(py::init<>())
      .def_readwrite("objective", &SmoothingOptions::objective, "SmoothingObjective (plan_step's smoother)")
      .def_readwrite("torque_resolution", &SmoothingOptions::torque_resolution,
                     "PeakTorque: edge samples every this [rad], [1e-3, 1]")
      .def_readwrite("torque_tolerance", &SmoothingOptions::torque_tolerance,
                     "PeakTorque: peaks closer than this tie (fraction of a limit), [0, 1]")
      .def_readwrite("epsilon", &SmoothingOptions::epsilon, "[rad]")
      .def_readwrite("min_improvement", &SmoothingOptions::min_improvement, "relative")
      .def_readwrite("max_iterations", &SmoothingOptions::max_iterations)
      .def_readwrite("max_nodes", &SmoothingOptions::max_nodes)
      .def("validate", &SmoothingOptions::validate, "Raise ValueError naming the field.");
  py::class_<SmoothingResult>(m, "SmoothingResult", "A smoothed path.")
      .def_readonly("path", &SmoothingResult::path)
      .def_readonly("initial_length", &SmoothingResult::initial_length)
      .def_readonly("length", &SmoothingResult::length)
      .def_readonly("iterations", &SmoothingResult::iterations)
      .def_readonly("edge_checks", &SmoothingResult::edge_checks)
      .def_readonly("seconds", &SmoothingResult::seconds)
      .def_readonly("initial_peak_saturation", &SmoothingResult::initial_peak_saturation,
                    "peak |tau| / limit along the input (NaN unless PeakTorque)")
      .def_readonly("peak_saturation", &SmoothingResult::peak_saturation,
                    "peak |tau| / limit along the result (NaN unless PeakTorque)");
  py::class_<TorquePeak>(m, "TorquePeak", "Peak |tau| / limit over every joint of every leg, and where.")
      .def_readonly("saturation", &TorquePeak::saturation, "1 = a joint at its torque limit")
      .def_readonly("leg", &TorquePeak::leg)
      .def_readonly("joint", &TorquePeak::joint);
  py::class_<StanceTorques>(m, "StanceTorques",
                            "Static joint torques of a stance as one leg steps (§7.1): zero-interaction loads "
                            "(§5.1.1), tau = J^T f + g(q) (§5.3.2-5.3.3).")
      .def(py::init([](const WalkerModel& model, const Eigen::Matrix4d& body, const Eigen::MatrixXd& q, int leg) {
             return std::make_unique<StanceTorques>(model, body_pose(body), q, leg);
           }),
           "model"_a, "body"_a, "q"_a, "leg"_a, py::keep_alive<1, 2>())
      .def("down", guarded("StanceTorques.down", &StanceTorques::down), "q_leg"_a,
           "Every foot down, the swing wheel on q_leg's contact (after the step).")
      .def("lifted", guarded("StanceTorques.lifted", &StanceTorques::lifted), "q_leg"_a,
           "The swing leg in the air at q_leg, the other feet carry the robot.")
      .def("lifted_segment", guarded("StanceTorques.lifted_segment", &StanceTorques::lifted_segment), "a"_a, "b"_a,
           "resolution"_a = 0.05, "Peak of lifted() along a -> b, sampled every resolution [rad].")
      .def("lifted_path", guarded("StanceTorques.lifted_path", &StanceTorques::lifted_path), "path"_a,
           "resolution"_a = 0.05, "Peak of lifted() along a (joints, waypoints) path.")
      .def_property_readonly("leg", &StanceTorques::leg);
  m.def("smooth_path_for_torque",
        [](LegCollisionChecker& checker, StanceTorques& torques, const Eigen::Ref<const Eigen::MatrixXd>& path,
           const SmoothingOptions& options) {
          const Busy busy("smooth_path_for_torque", {&checker, &torques});
          return smooth_path_for_torque(checker, torques, path, options);
        },
        "checker"_a, "torques"_a, "path"_a, "options"_a = SmoothingOptions{},
        py::call_guard<py::gil_scoped_release, interruptible>(),
        "Dijkstra-bisection smoothing for the smallest peak joint torque, then length (§7.1, §3.4.2).");
  m.def("smooth_path",
        [](LegCollisionChecker& checker, const Eigen::Ref<const Eigen::MatrixXd>& path,
           const SmoothingOptions& options) {
          const Busy busy("smooth_path", {&checker});
          return smooth_path(checker, path, options);
        },
        "checker"_a, "path"_a, "options"_a = SmoothingOptions{},
        py::call_guard<py::gil_scoped_release, interruptible>(), "Fig. 4: Dijkstra over shortcuts, bisection, repeat.");

  py::class_<SwingSagOptions>(m, "SwingSagOptions", "Sag of the swing stance (§4.1, §5.1).")
      .def(py::init<>())
      .def_readwrite("stiffness", &SwingSagOptions::stiffness, "[N/m]")
      .def_readwrite("lift_height", &SwingSagOptions::lift_height, "[m]")
      .def_readwrite("sag", &SwingSagOptions::sag, "statics.SagOptions")
      .def("validate", &SwingSagOptions::validate, "Raise ValueError naming the field.");
  py::class_<SwingSag>(m, "SwingSag", "Predicted sag while one leg swings.")
      .def_readonly("status", &SwingSag::status)
      .def_property_readonly("rigid_body", [](const SwingSag& s) { return matrix(s.rigid_body); })
      .def_property_readonly("sagged_body", [](const SwingSag& s) { return matrix(s.sagged_body); })
      .def_readonly("hip_displacement", &SwingSag::hip_displacement, "[m]")
      .def_readonly("hip_drop", &SwingSag::hip_drop, "[m] per hip, > 0 down")
      .def_readonly("forces", &SwingSag::forces, "[N] (3, legs)")
      .def_readonly("lifted_q", &SwingSag::lifted_q);
  m.def("predict_swing_sag",
        [](const WalkerModel& model, const Eigen::Matrix4d& body, const Eigen::MatrixXd& q, int leg,
           const SwingSagOptions& options) {
          const Eigen::Isometry3d b = body_pose(body);
          py::gil_scoped_release release;
          interruptible scope;
          return predict_swing_sag(model, b, q, leg, options);
        },
        "model"_a, "body"_a, "q"_a, "leg"_a, "options"_a = SwingSagOptions{},
        "The sagged body pose (4 x 4, sagged_body) the planner plans against while `leg` swings.");

  py::class_<StepOptions>(m, "StepOptions", "Options of one planned step.")
      .def(py::init<>())
      .def_readwrite("collision", &StepOptions::collision)
      .def_readwrite("planner", &StepOptions::planner)
      .def_readwrite("smoothing", &StepOptions::smoothing)
      .def_readwrite("sag", &StepOptions::sag)
      .def_readwrite("map", &StepOptions::map)
      .def_readwrite("sag_compensation", &StepOptions::sag_compensation)
      .def("validate", &StepOptions::validate, "joints"_a, "Raise ValueError naming the field.");
  py::class_<StepPlan>(m, "StepPlan", "One planned step (or none, with the reason).")
      .def_readonly("status", &StepPlan::status)
      .def_readonly("reason", &StepPlan::reason)
      .def_readonly("sag", &StepPlan::sag)
      .def_property_readonly("planning_body", [](const StepPlan& s) { return matrix(s.planning_body); })
      .def_readonly("goal", &StepPlan::goal)
      .def_readonly("goal_margin", &StepPlan::goal_margin)
      .def_readonly("goal_saturation", &StepPlan::goal_saturation,
                    "peak |tau| / limit of the goal's stances (NaN when torques are off)")
      .def_readonly("path_saturation", &StepPlan::path_saturation,
                    "peak |tau| / limit along the path with the leg in the air (NaN when torques are off)")
      .def_readonly("q_start", &StepPlan::q_start)
      .def_readonly("q_start_above", &StepPlan::q_start_above)
      .def_readonly("q_goal_above", &StepPlan::q_goal_above)
      .def_readonly("q_goal", &StepPlan::q_goal)
      .def_readonly("plan", &StepPlan::plan)
      .def_readonly("smoothing", &StepPlan::smoothing)
      .def_readonly("path", &StepPlan::path)
      .def_property_readonly("solved", [](const StepPlan& s) { return s.status == PlanStatus::kSolved; });
  m.def("plan_step",
        [](const WalkerModel& model, const HeightMap& terrain, const Eigen::Matrix4d& body,
           const Eigen::MatrixXd& q, int leg, double goal_x, double goal_y, const StepOptions& options) {
          const Eigen::Isometry3d b = body_pose(body);
          py::gil_scoped_release release;
          interruptible scope;
          return plan_step(model, terrain, b, q, leg, goal_x, goal_y, options);
        },
        "model"_a, "terrain"_a, "body"_a, "q"_a, "leg"_a, "goal_x"_a, "goal_y"_a, "options"_a = StepOptions{},
        "Sag-compensated step of `leg` to the ground below (goal_x, goal_y).");

  py::class_<RockFieldOptions>(m, "RockFieldOptions", "Rock field on flat ground (D-RATS-like, §6).")
      .def(py::init<>())
      .def_readwrite("length", &RockFieldOptions::length)
      .def_readwrite("centre_x", &RockFieldOptions::centre_x)
      .def_readwrite("centre_y", &RockFieldOptions::centre_y)
      .def_readwrite("spacing", &RockFieldOptions::spacing)
      .def_readwrite("rocks", &RockFieldOptions::rocks)
      .def_readwrite("min_height", &RockFieldOptions::min_height)
      .def_readwrite("max_height", &RockFieldOptions::max_height)
      .def_readwrite("min_radius", &RockFieldOptions::min_radius)
      .def_readwrite("max_radius", &RockFieldOptions::max_radius)
      .def_readwrite("keep_clear", &RockFieldOptions::keep_clear)
      .def_readwrite("inner_radius", &RockFieldOptions::inner_radius)
      .def_readwrite("seed", &RockFieldOptions::seed)
      .def("validate", &RockFieldOptions::validate, "Raise ValueError naming the field.");
  m.def("rock_field", &rock_field, "options"_a, "keep_clear"_a,
        "Height map of rocks on flat ground; none within keep_clear of the (2, k) points.");
  m.def("sample_waypoints",
        [](StabilityMapper& mapper, const StabilityMap& map, LegCollisionChecker& checker, int count,
           std::uint32_t seed) {
          const Busy busy("sample_waypoints", {&mapper, &checker});
          return sample_waypoints(mapper, map, checker, count, seed);
        },
        "mapper"_a, "map"_a, "checker"_a, "count"_a, "seed"_a,
        py::call_guard<py::gil_scoped_release, interruptible>(),
        "(joints, count) collision-free waypoints above random stable cells.");
  bind_footfall_terrain(m);  // the planner's DEM from the stereo map
}

}  // namespace ernest::bindings
