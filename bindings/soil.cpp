// Python bindings of cpp/soil. Argument names equal the C++ names.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "bindings.hpp"
#include "interrupt.hpp"
#include "ernest/common/validation.hpp"
#include "ernest/soil/bekker_wong.hpp"
#include "ernest/soil/rigid_contact.hpp"
#include "ernest/soil/single_wheel.hpp"
#include "ernest/soil/soil_parameters.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::soil;

void bind_soil(py::module_& m) {
  py::class_<SoilParameters>(m, "SoilParameters",
                             "Bekker–Wong soil parameters in SI units (seed 004 Table 2). "
                             "Defaults are the M90 Mars simulant.")
      .def(py::init<>())
      .def_readwrite("density", &SoilParameters::density, "rho [kg/m^3]")
      .def_readwrite("cohesion", &SoilParameters::cohesion, "c [Pa]")
      .def_readwrite("friction_angle", &SoilParameters::friction_angle, "phi [rad]")
      .def_readwrite("sinkage_exponent", &SoilParameters::sinkage_exponent, "n [-]")
      .def_readwrite("k_c", &SoilParameters::k_c, "cohesion modulus [N/m^(n+1)]")
      .def_readwrite("k_phi", &SoilParameters::k_phi, "friction modulus [N/m^(n+2)]")
      .def_readwrite("shear_modulus_x", &SoilParameters::shear_modulus_x, "K_x [m]")
      .def_readwrite("shear_modulus_y", &SoilParameters::shear_modulus_y, "K_y [m]")
      .def_readwrite("a0", &SoilParameters::a0, "theta_m coefficient a0 (eq 14)")
      .def_readwrite("a1", &SoilParameters::a1, "theta_m coefficient a1 (eq 14)")
      .def_readwrite("b0", &SoilParameters::b0, "theta_r coefficient b0 (eq 15)")
      .def_readwrite("b1", &SoilParameters::b1, "theta_r coefficient b1 (eq 15)")
      .def_readwrite("eps_slip", &SoilParameters::eps_slip, "slip regularisation [(m/s)^-2] (eq 12)")
      .def_readwrite("eps_motion", &SoilParameters::eps_motion, "rest threshold [m/s] (eq 16)")
      .def_readwrite("eps_contact_x", &SoilParameters::eps_contact_x, "[m/s] (eq 28)")
      .def_readwrite("eps_contact_y", &SoilParameters::eps_contact_y, "[m/s] (eq 29)")
      .def_readwrite("eps_direction", &SoilParameters::eps_direction,
                     "regularisation of sign(v_x) in eqs 30, 32 [m/s]; 0 = the paper's sign")
      .def_readwrite("slip_clamp_first", &SoilParameters::slip_clamp_first,
                     "eq 12 braking ratio clamped before the regularisation (ours; False = as "
                     "printed)")
      .def_readwrite("gravity", &SoilParameters::gravity, "[m/s^2], for the unit weight in eq 24")
      .def("validate", &SoilParameters::validate,
           "Raise ValueError naming the first field outside its allowed range.")
      .def_static("dry_sand", &SoilParameters::dry_sand, "Table 2, dry sand.")
      .def_static("m90", &SoilParameters::m90, "Table 2, M90 Mars simulant.")
      .def_static("wet_sand", &SoilParameters::wet_sand,
                  "Wet sand (our assumption; higher cohesion, softer than M90).")
      .def_static("preset", &SoilParameters::preset, "name"_a,
                  "Preset by name: 'dry_sand', 'm90' or 'wet_sand'.")
      .def_static("preset_names", &SoilParameters::preset_names, "Names accepted by preset().");

  py::class_<WheelGeometry>(m, "WheelGeometry", "Rigid wheel: radius r and width b [m].")
      .def(py::init<>())
      .def(py::init([](double radius, double width) { return WheelGeometry{radius, width}; }),
           "radius"_a, "width"_a)
      .def_readwrite("radius", &WheelGeometry::radius)
      .def_readwrite("width", &WheelGeometry::width)
      .def("validate", &WheelGeometry::validate, "Raise ValueError on an invalid field.");

  py::class_<ContactState>(m, "ContactState",
                           "Wheel kinematics in the contact frame of seed 004 Fig. 7.")
      .def(py::init<>())
      .def(py::init([](double sinkage, double vx, double vy, double vcx, double vcy) {
             return ContactState{sinkage, vx, vy, vcx, vcy};
           }),
           "sinkage"_a, "vx"_a = 0.0, "vy"_a = 0.0, "vcx"_a = 0.0, "vcy"_a = 0.0)
      .def_readwrite("sinkage", &ContactState::sinkage, "h [m]")
      .def_readwrite("vx", &ContactState::vx, "wheel-centre longitudinal velocity [m/s]")
      .def_readwrite("vy", &ContactState::vy, "wheel-centre lateral velocity [m/s]")
      .def_readwrite("vcx", &ContactState::vcx, "contact-point longitudinal velocity [m/s]")
      .def_readwrite("vcy", &ContactState::vcy, "contact-point lateral velocity [m/s]");

  py::class_<WheelSoilForce>(m, "WheelSoilForce", "Soil force on a wheel plus diagnostics.")
      .def_readonly("fx", &WheelSoilForce::fx, "eq 30 [N]")
      .def_readonly("fy", &WheelSoilForce::fy, "eq 31 [N]")
      .def_readonly("fz", &WheelSoilForce::fz, "eq 32 [N]")
      .def_readonly("axle_torque", &WheelSoilForce::axle_torque, "r^2 b int tau_x [N m]")
      .def_readonly("slip", &WheelSoilForce::slip, "eq 12")
      .def_readonly("theta_f", &WheelSoilForce::theta_f, "eq 13 [rad]")
      .def_readonly("theta_m", &WheelSoilForce::theta_m, "eq 14 [rad]")
      .def_readonly("theta_r", &WheelSoilForce::theta_r, "eq 15 [rad]")
      .def_readonly("sinkage", &WheelSoilForce::sinkage, "sinkage used, clamped to [0, r] [m]");

  py::class_<BekkerWongModel>(m, "BekkerWongModel",
                              "Bekker–Wong wheel–soil model with the DARTS changes (eqs 12–32).")
      .def(py::init<const SoilParameters&, const WheelGeometry&, int>(), "soil"_a,
           "wheel"_a = WheelGeometry{}, "points_per_panel"_a = BekkerWongModel::kDefaultPointsPerPanel)
      .def("evaluate", &BekkerWongModel::evaluate, "state"_a,
           "Force on one wheel; ValueError on non-finite input.")
      .def("evaluate_batch",
           [](const BekkerWongModel& self,
              const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 5, Eigen::RowMajor>>& states) {
             Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> forces(states.rows(), 4);
             {
               py::gil_scoped_release release;
               interruptible scope;  // Ctrl-C every few thousand rows
               self.evaluate_batch(states, forces);
             }
             return forces;
           },
           "states"_a,
           "Rows (sinkage, vx, vy, vcx, vcy) -> rows (fx, fy, fz, axle_torque); releases the GIL.")
      .def_property_readonly("soil", &BekkerWongModel::soil)
      .def_property_readonly("wheel", &BekkerWongModel::wheel)
      .def_property_readonly("points_per_panel", &BekkerWongModel::points_per_panel);
  m.attr("DEFAULT_POINTS_PER_PANEL") = BekkerWongModel::kDefaultPointsPerPanel;

  m.def("slip_ratio",
        [](double vx, double vcx, double eps_slip, bool clamp_first) {
          // Checked here, not in slip_ratio itself: the simulator calls it per wheel and step.
          ernest::require_finite("slip_ratio", "vx", vx);
          ernest::require_finite("slip_ratio", "vcx", vcx);
          ernest::require_in_range("slip_ratio", "eps_slip", eps_slip, 0.0, ernest::kInf);
          return slip_ratio(vx, vcx, eps_slip, clamp_first);
        },
        "vx"_a, "vcx"_a, "eps_slip"_a, "clamp_first"_a = true,
        "Regularised slip ratio of eq 12, clamped to [-1, 1] (clamp_first: see "
        "SoilParameters.slip_clamp_first).");

  py::class_<RigidContactParameters>(m, "RigidContactParameters",
                                     "Spring–damper rigid contact of seed 004 §3.4.")
      .def(py::init<>())
      .def_readwrite("stiffness", &RigidContactParameters::stiffness, "[N/m]")
      .def_readwrite("damping", &RigidContactParameters::damping, "[N s/m]")
      .def_readwrite("friction_min", &RigidContactParameters::friction_min)
      .def_readwrite("friction_max", &RigidContactParameters::friction_max)
      .def("validate", &RigidContactParameters::validate, "Raise ValueError on an invalid field.")
      .def("erp", &RigidContactParameters::erp, "dt"_a, "ODE ERP equivalent for step dt.")
      .def("cfm", &RigidContactParameters::cfm, "dt"_a, "ODE CFM equivalent for step dt.");

  py::class_<RigOptions>(m, "RigOptions", "Options of the single-wheel rig.")
      .def(py::init<>())
      .def_readwrite("carriage_speed", &RigOptions::carriage_speed, "[m/s]")
      .def_readwrite("sinkage_tolerance", &RigOptions::sinkage_tolerance, "[m]")
      .def_readwrite("max_iterations", &RigOptions::max_iterations)
      .def("validate", &RigOptions::validate, "Raise ValueError on an invalid field.");

  py::class_<RigResult>(m, "RigResult", "Equilibrium of the single-wheel rig at one slip.")
      .def_readonly("slip", &RigResult::slip)
      .def_readonly("model_slip", &RigResult::model_slip)
      .def_readonly("sinkage", &RigResult::sinkage)
      .def_readonly("drawbar_pull", &RigResult::drawbar_pull)
      .def_readonly("lateral_force", &RigResult::lateral_force)
      .def_readonly("normal_force", &RigResult::normal_force)
      .def_readonly("torque", &RigResult::torque)
      .def_readonly("theta_f", &RigResult::theta_f)
      .def_readonly("theta_m", &RigResult::theta_m)
      .def_readonly("theta_r", &RigResult::theta_r)
      .def_readonly("iterations", &RigResult::iterations)
      .def_readonly("converged", &RigResult::converged);

  m.def("rig_state",
        [](double sinkage, double slip, double carriage_speed, double wheel_radius) {
          // Checked here, not in rig_state itself: the equilibrium solver calls it per evaluation.
          ernest::require_finite("rig_state", "sinkage", sinkage);
          ernest::require_finite("rig_state", "carriage_speed", carriage_speed);
          ernest::require_finite("rig_state", "wheel_radius", wheel_radius);
          if (!(slip >= -1.0 && slip < 1.0))  // slip 1: the wheel would spin infinitely fast
            throw std::invalid_argument("rig_state.slip = " + std::to_string(slip) +
                                        " is outside the allowed range [-1, 1)");
          const ContactState st = rig_state(sinkage, slip, carriage_speed, wheel_radius);
          if (!std::isfinite(st.vcx))
            throw std::invalid_argument("rig_state: carriage_speed / (1 - slip) overflows (carriage_speed = " +
                                        std::to_string(carriage_speed) + ", slip = " + std::to_string(slip) + ")");
          return st;
        },
        "sinkage"_a, "slip"_a, "carriage_speed"_a, "wheel_radius"_a,
        "Contact state of a rig wheel at sinkage h and kinematic slip s in [-1, 1).");
  m.def("solve_equilibrium", &solve_equilibrium, "model"_a, "load"_a, "slip"_a,
        "options"_a = RigOptions{}, "Equilibrium sinkage (F_z = load) at one slip.");
  m.def("slip_sweep",
        [](const BekkerWongModel& model, double load, const Eigen::VectorXd& slips,
           const RigOptions& options) {
          py::gil_scoped_release release;
          return slip_sweep(model, load, slips, options);
        },
        "model"_a, "load"_a, "slips"_a, "options"_a = RigOptions{},
        "Rows (slip, model_slip, sinkage, drawbar_pull, normal_force, torque, converged).");
}

}  // namespace ernest::bindings
