// Python bindings of ERNEST's statics (seed 004 §3.2 eq 11, Fig. 25): mass model, its LM fit, the
// simulated load survey and the lift-off roll torque LP. Argument names equal the C++ names; the
// survey and the fit release the GIL.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "interrupt.hpp"
#include "ernest/dynamics/rover_sim.hpp"
#include "ernest/statics/liftoff.hpp"
#include "ernest/statics/load_survey.hpp"
#include "ernest/statics/mass_model.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::statics;

void bind_statics_rover(py::module_& m) {
  py::class_<MassModel>(m, "MassModel",
                        "ERNEST's two-body mass model (seed 004 §3.2, eq 11): chassis (with the "
                        "rear wheel assemblies) and bogie assembly (with the front ones), rover "
                        "frame of RoverParameters.")
      .def(py::init<>())
      .def_readwrite("chassis_mass", &MassModel::chassis_mass, "m_c [kg]")
      .def_readwrite("bogie_mass", &MassModel::bogie_mass, "m_b [kg]")
      .def_readwrite("chassis_com", &MassModel::chassis_com, "(x_c, y_c, z_c) [m], rover frame")
      .def_readwrite("bogie_com_height", &MassModel::bogie_com_height,
                     "z_b [m] above the axles, in the bogie's median and transverse planes")
      .def("validate", &MassModel::validate, "Raise ValueError naming the first invalid field.")
      .def("vector", &MassModel::vector, "(m_c, m_b, x_c, y_c, z_c, z_b) as an array.")
      .def_static("from_vector", &MassModel::from_vector, "v"_a,
                  "Model from (m_c, m_b, x_c, y_c, z_c, z_b).")
      .def_static("from_parameters", &MassModel::from_parameters, "p"_a,
                  "The simulator's own model: RoverParameters' bodies grouped as §3.2 groups them.")
      .def("__repr__", [](const MassModel& x) {
        return "MassModel(m_c=" + format_number(x.chassis_mass) + " kg, m_b=" +
               format_number(x.bogie_mass) + " kg, com=(" + format_number(x.chassis_com.x()) +
               ", " + format_number(x.chassis_com.y()) + ", " + format_number(x.chassis_com.z()) +
               ") m, z_b=" + format_number(x.bogie_com_height) + " m)";
      });
  m.attr("MASS_MODEL_PARAMETERS") = py::cast(std::vector<std::string>(
      mass_model_parameter_names().begin(), mass_model_parameter_names().end()));

  py::class_<RoverGeometry>(m, "RoverGeometry",
                            "Fixed geometry of the mass model (Table 1, gimbal point, tyre torus).")
      .def(py::init<>())
      .def_readwrite("wheelbase", &RoverGeometry::wheelbase, "[m]")
      .def_readwrite("track", &RoverGeometry::track, "[m]")
      .def_readwrite("wheel_radius", &RoverGeometry::wheel_radius, "[m]")
      .def_readwrite("tube_radius", &RoverGeometry::tube_radius, "tyre torus tube radius b/2 [m]")
      .def_readwrite("gimbal_height", &RoverGeometry::gimbal_height, "above the front axle [m]")
      .def_readwrite("gravity", &RoverGeometry::gravity, "[m/s^2]")
      .def("validate", &RoverGeometry::validate, "Raise ValueError naming the first invalid field.")
      .def_static("from_parameters", &RoverGeometry::from_parameters, "p"_a, "gravity"_a = 9.81,
                  "Geometry of a dynamics.RoverParameters.");

  py::class_<LoadPose>(m, "LoadPose",
                       "A static configuration (chassis attitude, gimbal psi/phi, roll torque, "
                       "ground normal) and its measured vertical wheel loads (FL, FR, RL, RR).")
      .def(py::init<>())
      .def_readwrite("chassis_quaternion", &LoadPose::chassis_quaternion, "(w, x, y, z), world")
      .def_readwrite("psi", &LoadPose::psi, "gimbal yaw [rad]")
      .def_readwrite("phi", &LoadPose::phi, "gimbal roll [rad]")
      .def_readwrite("roll_torque", &LoadPose::roll_torque,
                     "roll actuator torque on the bogie [N m] (0: clutch open)")
      .def_readwrite("ground_normal", &LoadPose::ground_normal, "world; locates the contact points")
      .def_readwrite("loads", &LoadPose::loads, "measured vertical loads [N], FL FR RL RR")
      .def_readwrite("horizontal_forces", &LoadPose::horizontal_forces,
                     "2x4: world x, y of each wheel's ground force [N] (zero: eq 11 as printed)")
      .def("validate", &LoadPose::validate, "index"_a = py::none(),
           "Raise ValueError naming the first invalid field (as poses[index] with an index).");

  py::class_<LoadEquations>(m, "LoadEquations",
                            "Statics of a pose: A f = b + t tau (force balance, moments about world "
                            "x and y, moment about the roll axis on the bogie).")
      .def_readonly("A", &LoadEquations::A)
      .def_readonly("b", &LoadEquations::b)
      .def_readonly("t", &LoadEquations::t)
      .def_readonly("contact", &LoadEquations::contact, "contact points from the rover origin");
  m.def("load_equations", &load_equations, "model"_a, "geometry"_a, "pose"_a,
        "The linear statics A f = b + t tau of a pose for a mass model.");
  m.def("predict_loads", &predict_loads, "model"_a, "geometry"_a, "pose"_a,
        "Vertical wheel loads [N] (FL, FR, RL, RR) the mass model predicts for the pose and its "
        "roll torque (eq 11's f̂_z,i).");

  py::class_<MassFitOptions>(m, "MassFitOptions", "Levenberg–Marquardt settings of the eq 11 fit.")
      .def(py::init<>())
      .def_readwrite("max_evaluations", &MassFitOptions::max_evaluations)
      .def_readwrite("tolerance", &MassFitOptions::tolerance)
      .def_readwrite("fixed", &MassFitOptions::fixed,
                     "6 bools: parameters held at the initial value (MassModel.vector() order)")
      .def("validate", &MassFitOptions::validate, "Raise ValueError naming the first invalid field.");
  py::class_<MassFitResult>(m, "MassFitResult",
                            "Fitted model, 1-sigma errors (inf: not identifiable from the poses), "
                            "covariance, R^2 (paper: 0.96), RMSE, LM status.")
      .def_readonly("model", &MassFitResult::model)
      .def_readonly("std_error", &MassFitResult::std_error, "inf for a parameter not identifiable")
      .def_readonly("covariance", &MassFitResult::covariance,
                    "NaN in the rows and columns of a parameter not identifiable")
      .def_readonly("r_squared", &MassFitResult::r_squared)
      .def_readonly("rmse", &MassFitResult::rmse)
      .def_readonly("residual_sigma", &MassFitResult::residual_sigma)
      .def_readonly("evaluations", &MassFitResult::evaluations)
      .def_readonly("rank", &MassFitResult::rank)
      .def_readonly("identifiable", &MassFitResult::identifiable)
      .def_readonly("converged", &MassFitResult::converged)
      .def_readonly("status", &MassFitResult::status);
  m.def("fit_mass_model", &fit_mass_model, "poses"_a, "geometry"_a, "initial"_a = MassModel{},
        "options"_a = MassFitOptions{}, py::call_guard<py::gil_scoped_release, interruptible>(),
        "Fit (m_c, m_b, x_c, y_c, z_c, z_b) to the poses' loads by Levenberg–Marquardt (seed 004 "
        "eq 11; Eigen's LM, analytic Jacobian); uncertainty from the Jacobian at the optimum.");

  py::class_<SurveyOptions>(m, "SurveyOptions",
                            "Poses of the simulated load survey: gimbal yaws, slopes, headings, "
                            "blocks under single wheels, settling time.")
      .def(py::init<>())
      .def_readwrite("yaws_deg", &SurveyOptions::yaws_deg)
      .def_readwrite("slopes_deg", &SurveyOptions::slopes_deg)
      .def_readwrite("headings_deg", &SurveyOptions::headings_deg)
      .def_readwrite("block_height", &SurveyOptions::block_height, "[m], 0: no blocks")
      .def_readwrite("settle_time", &SurveyOptions::settle_time, "[s]")
      .def_readwrite("average_time", &SurveyOptions::average_time, "[s]")
      .def_readwrite("friction", &SurveyOptions::friction)
      .def("validate", &SurveyOptions::validate, "Raise ValueError naming the first invalid field.");
  m.def("survey_loads", &survey_loads, "params"_a, "options"_a = SurveyOptions{},
        py::call_guard<py::gil_scoped_release, interruptible>(),
        "Settle the simulated rover in each survey pose (AGS off, clutch open, rigid ground) and "
        "read each wheel's vertical ground force from its force–torque sensor (§3.2, Fig. 6).");

  m.def("pose_from_state", &pose_from_state, "params"_a, "state"_a, "gravity"_a,
        "ground_normal"_a = Eigen::Vector3d::UnitZ(),
        "The LoadPose of a simulator state: attitude, gimbal angles, roll torque, and each wheel's "
        "ground force from its FTS plus the wheel assembly's weight (loads and horizontal_forces).");

  py::class_<LiftoffOptions>(m, "LiftoffOptions", "Lift-off LP settings.")
      .def(py::init<>())
      .def_readwrite("min_load", &LiftoffOptions::min_load, "a wheel lifts below this load [N]")
      .def_readwrite("torque_limit", &LiftoffOptions::torque_limit, "|tau| bound [N m] (inf: none)")
      .def("validate", &LiftoffOptions::validate, "Raise ValueError naming the first invalid field.");
  py::class_<LiftoffLimit>(m, "LiftoffLimit", "One direction's roll-torque limit and its loads.")
      .def_readonly("torque", &LiftoffLimit::torque, "signed [N m], on the bogie about its x axis")
      .def_readonly("loads", &LiftoffLimit::loads, "FL FR RL RR at that torque [N]")
      .def_readonly("lifted_wheel", &LiftoffLimit::lifted_wheel, "0..3, -1 if torque-limited")
      .def_readonly("torque_limited", &LiftoffLimit::torque_limited);
  py::class_<LiftoffResult>(m, "LiftoffResult", "Both directions' limits (Fig. 25).")
      .def_readonly("feasible", &LiftoffResult::feasible)
      .def_readonly("loads_at_zero", &LiftoffResult::loads_at_zero)
      .def_readonly("positive", &LiftoffResult::positive)
      .def_readonly("negative", &LiftoffResult::negative);
  m.def("max_roll_torque", &max_roll_torque, "model"_a, "geometry"_a, "pose"_a,
        "options"_a = LiftoffOptions{},
        "Largest and smallest roll torque before a wheel lifts off, and the loads then (seed 004 "
        "Fig. 25): two linear programs solved by GLPK on the mass model's statics.");
  m.def("slope_pose", &slope_pose, "slope"_a, "heading"_a, "psi"_a,
        "Pose of the rover with its four wheels on a plane rising along +x at `slope` [rad], "
        "heading [rad] from uphill, gimbal yaw psi [rad], roll 0.");
}

}  // namespace ernest::bindings
