// Python bindings of cpp/walker (seed 003: ATHLETE-class wheel-on-leg walker). Argument names
// equal the C++ names; poses are 4 × 4 homogeneous matrices; joint configurations of the whole
// robot are (joints per leg, legs) arrays.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "bindings.hpp"
#include "interrupt.hpp"
#include "exclusive.hpp"
#include "pose.hpp"
#include "ernest/walker/leg_ik.hpp"
#include "ernest/walker/self_collision.hpp"
#include "ernest/walker/stance_loads.hpp"
#include "ernest/walker/sway_gait.hpp"
#include "ernest/walker/walker_model.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::walker;

namespace {

Eigen::Matrix4d to_matrix(const Eigen::Isometry3d& t) { return t.matrix(); }

}  // namespace

void bind_walker(py::module_& m) {
  py::class_<Capsule>(m, "Capsule", "Segment p0–p1 swept by a sphere of `radius` (link frame).")
      .def(py::init<>())
      .def_readwrite("p0", &Capsule::p0, "[m]")
      .def_readwrite("p1", &Capsule::p1, "[m]")
      .def_readwrite("radius", &Capsule::radius, "[m]; 0 = no geometry");

  py::class_<JointSpec>(m, "JointSpec",
                        "One revolute joint and the link it moves: offset from the previous joint "
                        "(no rotation at q = 0), axis, limits, torque limit, link inertia, capsule.")
      .def(py::init<>())
      .def_readwrite("name", &JointSpec::name)
      .def_readwrite("offset", &JointSpec::offset, "[m] in the previous joint frame")
      .def_readwrite("axis", &JointSpec::axis, "unit axis")
      .def_readwrite("lower", &JointSpec::lower, "[rad]")
      .def_readwrite("upper", &JointSpec::upper, "[rad]")
      .def_readwrite("torque_limit", &JointSpec::torque_limit, "|tau| at saturation [N m]")
      .def_readwrite("mass", &JointSpec::mass, "link mass [kg]")
      .def_readwrite("com", &JointSpec::com, "link centre of mass in the joint frame [m]")
      .def_readwrite("inertia", &JointSpec::inertia, "principal inertia about the CoM [kg m^2]")
      .def_readwrite("geometry", &JointSpec::geometry, "collision capsule")
      .def("__repr__", [](const JointSpec& j) { return "JointSpec('" + j.name + "')"; });

  py::class_<WalkerParameters>(m, "WalkerParameters",
                               "Wheel-on-leg walker: hexagonal chassis, identical legs (seed 003 "
                               "§2.3). Use sdm_b_parameters() / t12_parameters() for the presets.")
      .def(py::init<>())
      .def_readwrite("name", &WalkerParameters::name)
      .def_readwrite("legs", &WalkerParameters::legs)
      .def_readwrite("hip_radius", &WalkerParameters::hip_radius, "[m]")
      .def_readwrite("chassis_mass", &WalkerParameters::chassis_mass, "[kg]")
      .def_readwrite("chassis_com", &WalkerParameters::chassis_com, "[m] body frame")
      .def_readwrite("chassis_inertia", &WalkerParameters::chassis_inertia, "[kg m^2]")
      .def_readwrite("chassis_collision_radius", &WalkerParameters::chassis_collision_radius, "[m]")
      .def_readwrite("chassis_collision_half_height",
                     &WalkerParameters::chassis_collision_half_height, "[m]")
      .def_readwrite("joints", &WalkerParameters::joints, "list of JointSpec, hip to wheel")
      .def_readwrite("foot_offset", &WalkerParameters::foot_offset,
                     "wheel centre in the last joint frame [m]")
      .def_readwrite("foot_rotation", &WalkerParameters::foot_rotation,
                     "foot frame axes in the last joint frame (z up the leg, y the axle)")
      .def_readwrite("wheel_radius", &WalkerParameters::wheel_radius, "[m]")
      .def_readwrite("wheel_width", &WalkerParameters::wheel_width, "[m]")
      .def_readwrite("standard_height", &WalkerParameters::standard_height,
                     "hip plane above the ground in the standard pose [m] (§5.1.4)")
      .def_readwrite("standard_foot_radius", &WalkerParameters::standard_foot_radius, "[m]")
      .def_readwrite("gravity", &WalkerParameters::gravity, "[m/s^2]")
      .def("validate", &WalkerParameters::validate,
           "Raise ValueError naming the first field outside its allowed range.")
      .def("joints_per_leg", &WalkerParameters::joints_per_leg)
      .def("total_mass", &WalkerParameters::total_mass, "[kg]");
  m.def("sdm_b_parameters", &sdm_b_parameters,
        "SDM-B (first-generation ATHLETE, six 6-DOF legs, 850 kg, 1.75 m standard height).");
  m.def("t12_parameters", &t12_parameters, "T12 (seven joints a leg, 2.15 m standard height).");

  py::class_<LinkCapsule>(m, "LinkCapsule", "A collision capsule of one link (link -1 = wheel).")
      .def_readonly("leg", &LinkCapsule::leg)
      .def_readonly("link", &LinkCapsule::link)
      .def_readonly("p0", &LinkCapsule::p0)
      .def_readonly("p1", &LinkCapsule::p1)
      .def_readonly("radius", &LinkCapsule::radius);

  py::class_<WalkerModel>(m, "WalkerModel",
                          "Immutable walker model: kinematics, contact Jacobians, static joint "
                          "torques tau = J^T f + g(q) and margins to saturation (Figs 15–16).")
      .def(py::init<const WalkerParameters&>(), "params"_a)
      .def_property_readonly("params", &WalkerModel::params)
      .def_property_readonly("legs", &WalkerModel::legs)
      .def_property_readonly("joints_per_leg", &WalkerModel::joints_per_leg)
      .def_property_readonly("lower_limits", &WalkerModel::lower_limits, "[rad]")
      .def_property_readonly("upper_limits", &WalkerModel::upper_limits, "[rad]")
      .def_property_readonly("torque_limits", &WalkerModel::torque_limits, "[N m]")
      .def_property_readonly("standard_configuration", &WalkerModel::standard_configuration,
                             "(joints, legs): every wheel upright at standard_foot_radius")
      .def("standard_body_pose", [](const WalkerModel& w) { return to_matrix(w.standard_body_pose()); },
           "4 × 4 body pose of the standard stance (hips standard_height above z = 0).")
      .def("hip_mount", [](const WalkerModel& w, int leg) { return to_matrix(w.hip_mount(leg)); },
           "leg"_a, "4 × 4 hip mount of a leg in the body frame.")
      .def("foot_pose",
           [](const WalkerModel& w, int leg, const Eigen::VectorXd& q) { return to_matrix(w.foot_pose(leg, q)); },
           "leg"_a, "q"_a, "4 × 4 foot frame (wheel centre; z up the leg, y the axle), body frame.")
      .def("contact_point", &WalkerModel::contact_point, "leg"_a, "q"_a,
           "Wheel contact point (wheel centre − radius · z_F), body frame [m].")
      .def("contact_jacobian",
           [](const WalkerModel& w, int leg, const Eigen::VectorXd& q) {
             w.check_leg(leg);
             w.check_q(q);
             LegWorkspace ws(w);
             w.forward(leg, q, ws);
             Eigen::Matrix3Xd J(3, w.joints_per_leg());
             w.contact_jacobian(ws, J);
             return J;
           },
           "leg"_a, "q"_a, "d contact_point / d q, shape (3, joints), body frame.")
      .def("foot_jacobian",
           [](const WalkerModel& w, int leg, const Eigen::VectorXd& q) {
             w.check_leg(leg);
             w.check_q(q);
             LegWorkspace ws(w);
             w.forward(leg, q, ws);
             Eigen::MatrixXd J(6, w.joints_per_leg());
             w.foot_jacobian(ws, J);
             return J;
           },
           "leg"_a, "q"_a, "Geometric Jacobian of the foot frame (wheel-centre velocity; angular), (6, joints).")
      .def("gravity_torques",
           [](const WalkerModel& w, int leg, const Eigen::VectorXd& q, const Eigen::Matrix3d& body_rotation) {
             return w.joint_torques(leg, q, Eigen::Vector3d::Zero(), body_rotation);
           },
           "leg"_a, "q"_a, "body_rotation"_a = Eigen::Matrix3d::Identity(),
           "g(q) = dV/dq: torques holding the leg's links against gravity [N m].")
      .def("joint_torques",
           [](const WalkerModel& w, int leg, const Eigen::VectorXd& q, const Eigen::Vector3d& reaction,
              const Eigen::Matrix3d& body_rotation) {
             return w.joint_torques(leg, q, reaction, body_rotation);
           },
           "leg"_a, "q"_a, "reaction"_a, "body_rotation"_a = Eigen::Matrix3d::Identity(),
           "Static torques tau = J^T f + g(q), f = -reaction; `reaction` is the ground's force on "
           "the wheel in the body frame [N]; body_rotation is the body's world rotation.")
      .def("saturation", &WalkerModel::saturation, "tau"_a,
           "|tau_i| / torque_limit_i per joint (1 = saturation).")
      .def("margin_to_saturation", &WalkerModel::margin_to_saturation, "tau"_a,
           "1 − max_i |tau_i| / torque_limit_i.")
      .def("gravity_in_body", &WalkerModel::gravity_in_body, "body_rotation"_a,
           "Gravity vector in the body frame [m/s^2].")
      .def("center_of_mass",
           [](const WalkerModel& w, const Eigen::Matrix4d& body, const Eigen::MatrixXd& q) {
             return w.center_of_mass(to_isometry(body, "body"), q);
           },
           "body"_a, "q"_a, "Whole-robot centre of mass in the world [m]; q has shape (joints, legs).")
      .def("contact_points",
           [](const WalkerModel& w, const Eigen::Matrix4d& body, const Eigen::MatrixXd& q) {
             return w.contact_points(to_isometry(body, "body"), q);
           },
           "body"_a, "q"_a, "Contact points of every leg in the world, shape (3, legs).")
      .def("leg_capsules", &WalkerModel::leg_capsules, "leg"_a, "q"_a,
           "Collision capsules of one leg (links, then the wheel), body frame.")
      .def("capsules",
           [](const WalkerModel& w, const Eigen::Matrix4d& body, const Eigen::MatrixXd& q) {
             return w.capsules(to_isometry(body, "body"), q);
           },
           "body"_a, "q"_a, "Collision capsules of every leg in the world.")
      .def("within_limits", &WalkerModel::within_limits, "q"_a, "tolerance"_a = 1e-9,
           "True when every joint is inside its limits.");

  py::class_<CollisionPair>(m, "CollisionPair",
                            "Two shapes within the clearance (link -1 = wheel; leg_b -1 = chassis).")
      .def_readonly("leg_a", &CollisionPair::leg_a)
      .def_readonly("link_a", &CollisionPair::link_a)
      .def_readonly("leg_b", &CollisionPair::leg_b)
      .def_readonly("link_b", &CollisionPair::link_b)
      .def_readonly("distance", &CollisionPair::distance, "[m], 0 when intersecting")
      .def("__repr__", [](const CollisionPair& c) {
        return "CollisionPair(" + std::to_string(c.leg_a) + ":" + std::to_string(c.link_a) + ", " +
               std::to_string(c.leg_b) + ":" + std::to_string(c.link_b) +
               ", distance=" + format_number(c.distance) + " m)";
      });
  m.attr("CHASSIS") = kChassis;
  m.def("self_collisions", &self_collisions, "model"_a, "q"_a, "clearance"_a = 0.0,
        "Pairs of link capsules (other legs, chassis, distant links of the same leg) within "
        "`clearance` [m] in configuration q (joints, legs), checked with FCL.");

  m.def("upright_foot_pose",
        [](const WalkerModel& w, const Eigen::Vector3d& contact, double heading, const Eigen::Vector3d& up) {
          return to_matrix(upright_foot_pose(w, contact, heading, up));
        },
        "model"_a, "contact"_a, "heading"_a, "up"_a = Eigen::Vector3d::UnitZ(),
        "4 × 4 foot target of an upright wheel touching `contact` (body frame), rolling along "
        "`heading` about `up`.");

  py::class_<IkOptions>(m, "IkOptions", "Multi-start Levenberg–Marquardt IK settings.")
      .def(py::init<>())
      .def_readwrite("seeds", &IkOptions::seeds, "starts (caller's seed, then a Halton set)")
      .def_readwrite("max_evaluations", &IkOptions::max_evaluations, "per start")
      .def_readwrite("position_tolerance", &IkOptions::position_tolerance, "[m]")
      .def_readwrite("orientation_tolerance", &IkOptions::orientation_tolerance, "[rad]")
      .def_readwrite("orientation_weight", &IkOptions::orientation_weight, "[m]")
      .def_readwrite("duplicate_tolerance", &IkOptions::duplicate_tolerance, "[rad]")
      .def_readwrite("max_solutions", &IkOptions::max_solutions)
      .def("validate", &IkOptions::validate, "Raise ValueError naming the first invalid field.");

  py::enum_<IkStatus>(m, "IkStatus", "Outcome of an IK solve.")
      .value("Solved", IkStatus::kSolved)
      .value("Unreachable", IkStatus::kUnreachable);

  py::class_<IkResult>(m, "IkResult", "Distinct IK solutions inside the limits, nearest first.")
      .def_readonly("status", &IkResult::status)
      .def_readonly("solutions", &IkResult::solutions, "list of joint vectors [rad]")
      .def_readonly("position_error", &IkResult::position_error, "[m]")
      .def_readonly("orientation_error", &IkResult::orientation_error, "[rad]")
      .def_readonly("closest", &IkResult::closest, "best joint vector (closest approach if unreachable)")
      .def_readonly("evaluations", &IkResult::evaluations)
      .def_property_readonly("solved", [](const IkResult& r) { return r.status == IkStatus::kSolved; });

  py::class_<LegIk>(m, "LegIk",
                    "IK workspace for one model (one per thread): the foot frame to a target, "
                    "joint limits respected (q = c + h sin u), several starts.")
      .def(py::init<const WalkerModel&, const IkOptions&>(), "model"_a, "options"_a = IkOptions{},
           py::keep_alive<1, 2>())
      .def_property_readonly("options", &LegIk::options)
      .def("solve",
           [](LegIk& ik, int leg, const Eigen::Matrix4d& target, const Eigen::VectorXd& seed) {
             const Eigen::Isometry3d t = to_isometry(target, "target");
             const Busy busy("LegIk.solve", {&ik});
             py::gil_scoped_release release;
             interruptible scope;  // Ctrl-C between starts and solver iterations
             return ik.solve(leg, t, seed);
           },
           "leg"_a, "target"_a, "seed"_a,
           "Every distinct solution for the 4 × 4 foot target (body frame) from `seed` and the "
           "Halton starts; status Unreachable (with the closest approach) when none.")
      .def("solve_from",
           [](LegIk& ik, int leg, const Eigen::Matrix4d& target, const Eigen::VectorXd& seed) {
             const Eigen::Isometry3d t = to_isometry(target, "target");
             Eigen::VectorXd q(seed.size());
             bool ok;
             const Busy busy("LegIk.solve_from", {&ik});
             {
               py::gil_scoped_release release;
               interruptible scope;
               ok = ik.solve_from(leg, t, seed, q);
             }
             return py::make_tuple(ok, q);
           },
           "leg"_a, "target"_a, "seed"_a, "One local solve from `seed`: (converged, q).")
      .def("last_position_error", guarded("LegIk.last_position_error", &LegIk::last_position_error), "[m]")
      .def("last_orientation_error", guarded("LegIk.last_orientation_error", &LegIk::last_orientation_error), "[rad]")
      .def("last_evaluations", guarded("LegIk.last_evaluations", &LegIk::last_evaluations));

  // ---- weight distribution (Fig. 16) and the sway gait (Fig. 15) ------------------------------
  py::class_<StanceLoads>(m, "StanceLoads",
                          "Zero-interaction contact forces of a stance and the joint torques they "
                          "and the links' weight cause (seed 003 §5.3.3, Fig. 16).")
      .def_readonly("reactions", &StanceLoads::reactions, "ground on wheel, world [N], (3, legs)")
      .def_readonly("torques", &StanceLoads::torques, "[N m], (joints, legs)")
      .def_readonly("saturation", &StanceLoads::saturation, "|tau| / limit, (joints, legs)")
      .def_readonly("center_of_mass", &StanceLoads::center_of_mass, "world [m]")
      .def_readonly("peak_saturation", &StanceLoads::peak_saturation, "max |tau| / limit")
      .def_readonly("peak_leg", &StanceLoads::peak_leg)
      .def_readonly("peak_joint", &StanceLoads::peak_joint)
      .def_readonly("peak_force", &StanceLoads::peak_force, "largest |reaction| [N]")
      .def_readonly("mean_force", &StanceLoads::mean_force, "mean |reaction| of loaded legs [N]")
      .def_readonly("loaded", &StanceLoads::loaded, "legs on the ground")
      .def_readonly("support_margin", &StanceLoads::support_margin, "SSM of the CG [m]")
      .def_readonly("equilibrium_residual", &StanceLoads::equilibrium_residual)
      .def("margin", &StanceLoads::margin, "1 − peak_saturation");
  m.def("stance_loads",
        [](const WalkerModel& w, const Eigen::Matrix4d& body, const Eigen::MatrixXd& q,
           const std::vector<int>& lifted) {
          return stance_loads(w, to_isometry(body, "body"), q, lifted);
        },
        "model"_a, "body"_a, "q"_a, "lifted"_a = std::vector<int>{},
        "Loads of a stance: body pose (4 × 4, world), q (joints, legs), the legs in the air.");
  m.def("lift_legs",
        [](const WalkerModel& w, const Eigen::Matrix4d& body, const Eigen::MatrixXd& q,
           const std::vector<int>& legs, double height) {
          return lift_legs(w, to_isometry(body, "body"), q, legs, height);
        },
        "model"_a, "body"_a, "q"_a, "legs"_a, "height"_a,
        "q with the listed legs' wheels raised by `height` [m] (IK from the current angles).");

  py::class_<SwayGaitOptions>(m, "SwayGaitOptions",
                              "Reverse-wave gait and sway optimisation settings (seed 003 §5.3.1–5.3.2).")
      .def(py::init<>())
      .def_readwrite("stride", &SwayGaitOptions::stride, "advance of each foot per cycle [m]")
      .def_readwrite("heading", &SwayGaitOptions::heading, "direction of travel [rad]")
      .def_readwrite("lift_height", &SwayGaitOptions::lift_height, "[m]")
      .def_readwrite("sequence", &SwayGaitOptions::sequence, "stepping order (legs)")
      .def_readwrite("max_shift_xy", &SwayGaitOptions::max_shift_xy, "[m]")
      .def_readwrite("max_shift_up", &SwayGaitOptions::max_shift_up, "[m]")
      .def_readwrite("max_shift_down", &SwayGaitOptions::max_shift_down, "[m]")
      .def_readwrite("min_support_margin", &SwayGaitOptions::min_support_margin, "SSM floor [m]")
      .def_readwrite("fd_step", &SwayGaitOptions::fd_step, "finite-difference step [m]")
      .def_readwrite("solver", &SwayGaitOptions::solver, "ernest_cpp.opt.SolverOptions (SLSQP)")
      .def("validate", &SwayGaitOptions::validate, "legs"_a,
           "Raise ValueError naming the first invalid field.");

  py::class_<GaitPhase>(m, "GaitPhase", "One step of the gait: the stepping leg lifted, body still.")
      .def_readonly("lifted_leg", &GaitPhase::lifted_leg)
      .def_readonly("body_position", &GaitPhase::body_position, "world [m]")
      .def_readonly("displacement", &GaitPhase::displacement, "from the reference gait [m]")
      .def_readonly("reachable", &GaitPhase::reachable)
      .def_readonly("peak_saturation", &GaitPhase::peak_saturation, "worst of the two instants")
      .def_readonly("peak_force", &GaitPhase::peak_force, "[N]")
      .def_readonly("support_margin", &GaitPhase::support_margin, "[m]")
      .def_readonly("lift_off", &GaitPhase::lift_off, "StanceLoads at lift-off")
      .def_readonly("touch_down", &GaitPhase::touch_down, "StanceLoads before touch-down")
      .def_readonly("q_lift_off", &GaitPhase::q_lift_off)
      .def_readonly("q_touch_down", &GaitPhase::q_touch_down);

  py::class_<SwayGaitResult>(m, "SwayGaitResult", "Reference and sway gaits (Fig. 15).")
      .def_readonly("reference", &SwayGaitResult::reference)
      .def_readonly("sway", &SwayGaitResult::sway)
      .def_readonly("reference_margin", &SwayGaitResult::reference_margin, "min over steps of 1 − peak")
      .def_readonly("sway_margin", &SwayGaitResult::sway_margin)
      .def_readonly("improvement", &SwayGaitResult::improvement, "sway_margin / reference_margin − 1")
      .def_readonly("peak_reduction", &SwayGaitResult::peak_reduction,
                    "1 − sway peak / reference peak (worst step)")
      .def_readonly("solver_status", &SwayGaitResult::solver_status)
      .def_readonly("evaluations", &SwayGaitResult::evaluations)
      .def_readonly("seconds", &SwayGaitResult::seconds);
  m.def("evaluate_gait_phase", &evaluate_gait_phase, "model"_a, "options"_a, "phase"_a,
        "displacement"_a, py::call_guard<py::gil_scoped_release, interruptible>(),
        "Step `phase` of the periodic gait with the body displaced by `displacement` [m].");
  m.def("optimise_sway_gait", &optimise_sway_gait, "model"_a, "options"_a = SwayGaitOptions{},
        py::call_guard<py::gil_scoped_release, interruptible>(),
        "Reference gait and the sway gait maximising the margin to saturation at every step.");
  bind_walker_gait(m);
}

}  // namespace ernest::bindings
