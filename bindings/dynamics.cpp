// Python bindings of cpp/dynamics. Argument names equal the C++ names; stepping releases the GIL.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <optional>

#include "bindings.hpp"
#include "ernest/common/validation.hpp"
#include "ernest/dynamics/batch_stepper.hpp"
#include "ernest/dynamics/rover_parameters.hpp"
#include "ernest/dynamics/rover_sim.hpp"
#include "ernest/dynamics/terrain.hpp"
#include "ernest/dynamics/wheel_sync.hpp"
#include "ernest/solver/ode_init.hpp"
#include "interrupt.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::dynamics;

namespace {

template <size_t N>
py::array_t<double> arr(const std::array<double, N>& a) {
  py::array_t<double> out(N);
  std::copy(a.begin(), a.end(), out.mutable_data());
  return out;
}

using RowMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

}  // namespace

void bind_dynamics(py::module_& m) {
  py::register_exception<SimulationDiverged>(m, "SimulationDiverged", PyExc_RuntimeError);

  py::class_<MotorParameters>(m, "MotorParameters",
                              "DC motor + gearbox (seed 004 §2.1.1, eq 40). Values are assumptions.")
      .def(py::init<>())
      .def_readwrite("torque_constant", &MotorParameters::torque_constant, "K_tau [N m/A]")
      .def_readwrite("resistance", &MotorParameters::resistance, "R [Ohm]")
      .def_readwrite("gear_ratio", &MotorParameters::gear_ratio, "N [-]")
      .def_readwrite("efficiency", &MotorParameters::efficiency, "gearbox efficiency [-]")
      .def_readwrite("current_limit", &MotorParameters::current_limit, "[A]")
      .def_readwrite("rotor_inertia", &MotorParameters::rotor_inertia, "[kg m^2], motor side")
      .def("max_output_torque", &MotorParameters::max_output_torque,
           "N eta K_tau I_max: the largest output torque [N m].");

  py::class_<MotorElectrical>(m, "MotorElectrical", "Winding current [A] and power [W] (eq 40).")
      .def_readonly("current", &MotorElectrical::current)
      .def_readonly("power", &MotorElectrical::power);
  // (finite inputs checked here, not in the C++ function: the step calls it with its own state,
  // whose NaN is reported as SimulationDiverged by the divergence check)
  m.def("motor_electrical",
        [](const MotorParameters& mp, double output_torque, double output_speed) {
          ernest::require_finite("motor_electrical", "output_torque", output_torque);
          ernest::require_finite("motor_electrical", "output_speed", output_speed);
          const MotorElectrical e = motor_electrical(mp, output_torque, output_speed);
          if (!std::isfinite(e.current) || !std::isfinite(e.power))  // e.g. 1e300 N m
            throw std::invalid_argument("motor_electrical: output_torque = " + std::to_string(output_torque) +
                                        " and output_speed = " + std::to_string(output_speed) +
                                        " overflow the current or power");
          return e;
        },
        "m"_a, "output_torque"_a, "output_speed"_a,
        "Current and electrical power P = I (R I + K_tau omega) (eq 40) for an output torque "
        "[N m] and speed [rad/s]; the gearbox efficiency applies in the direction power flows.");

  py::class_<RoverParameters>(m, "RoverParameters",
                              "ERNEST model parameters: Table 1 geometry plus documented "
                              "assumptions (mass split, inertias, gimbal, motors, sensors).")
      .def(py::init<>())
      .def_readwrite("wheelbase", &RoverParameters::wheelbase, "[m] (Table 1)")
      .def_readwrite("track", &RoverParameters::track, "[m] (Table 1)")
      .def_readwrite("wheel_radius", &RoverParameters::wheel_radius, "[m] (Table 1)")
      .def_readwrite("wheel_width", &RoverParameters::wheel_width, "[m] (Table 1)")
      .def_readwrite("chassis_mass", &RoverParameters::chassis_mass, "[kg] without rear wheels")
      .def_readwrite("bogie_mass", &RoverParameters::bogie_mass, "[kg] without front wheels")
      .def_readwrite("wheel_assembly_mass", &RoverParameters::wheel_assembly_mass, "[kg] each")
      .def_readwrite("chassis_com", &RoverParameters::chassis_com, "(x_c, y_c, z_c) [m], §3.2")
      .def_readwrite("bogie_com_height", &RoverParameters::bogie_com_height, "z_b [m], §3.2")
      .def_readwrite("chassis_inertia", &RoverParameters::chassis_inertia, "principal [kg m^2]")
      .def_readwrite("bogie_inertia", &RoverParameters::bogie_inertia, "principal [kg m^2]")
      .def_readwrite("wheel_spin_inertia", &RoverParameters::wheel_spin_inertia, "[kg m^2]")
      .def_readwrite("wheel_transverse_inertia", &RoverParameters::wheel_transverse_inertia)
      .def_readwrite("gimbal_height", &RoverParameters::gimbal_height, "[m] above the axles")
      .def_readwrite("yaw_limit", &RoverParameters::yaw_limit, "[rad]")
      .def_readwrite("roll_limit", &RoverParameters::roll_limit, "[rad]")
      .def_readwrite("stop_stiffness", &RoverParameters::stop_stiffness, "[N m/rad]")
      .def_readwrite("stop_damping", &RoverParameters::stop_damping, "[N m s/rad]")
      .def_readwrite("yaw_brake_torque", &RoverParameters::yaw_brake_torque, "[N m]")
      .def_readwrite("clutch_align_speed", &RoverParameters::clutch_align_speed, "[rad/s]")
      .def_readwrite("clutch_align_gain", &RoverParameters::clutch_align_gain, "[1/s]")
      .def_readwrite("clutch_align_tolerance", &RoverParameters::clutch_align_tolerance, "[rad]")
      .def_readwrite("wheel_motor", &RoverParameters::wheel_motor, "50:1 drive")
      .def_readwrite("gimbal_motor", &RoverParameters::gimbal_motor, "160:1 gimbal actuators")
      .def_readwrite("fts_height", &RoverParameters::fts_height, "sensor above wheel centre [m]")
      .def("validate", &RoverParameters::validate, "Raise ValueError naming an invalid field.")
      .def("total_mass", &RoverParameters::total_mass, "[kg]")
      .def("wheel_centre", &RoverParameters::wheel_centre, "i"_a,
           "Nominal centre of wheel i (0 FL, 1 FR, 2 RL, 3 RR) in the rover frame [m].")
      .def("gimbal_point", &RoverParameters::gimbal_point, "Gimbal centre in the rover frame [m].");

  py::class_<HeightMap>(m, "HeightMap",
                        "Height grid: heights[i, j] at (origin_x + i spacing, origin_y + j "
                        "spacing); bilinear height and normal; flat beyond the border.")
      .def(py::init<Eigen::MatrixXd, double, double, double>(), "heights"_a, "spacing"_a,
           "origin_x"_a, "origin_y"_a)
      .def_static("flat", &HeightMap::flat, "length"_a, "width"_a, "spacing"_a, "z"_a = 0.0,
                  "x0"_a = -5.0, "y0"_a = -5.0, "Flat ground at height z.")
      .def_static("slope", &HeightMap::slope, "angle"_a, "length"_a, "width"_a, "spacing"_a,
                  "x0"_a = -5.0, "y0"_a = -5.0, "Plane z = tan(angle) x rising along +x.")
      // (finite x, y checked here: the C++ queries are the simulation's hot path)
      .def("height",
           [](const HeightMap& hm, double x, double y) {
             ernest::require_finite("HeightMap.height", "x", x);
             ernest::require_finite("HeightMap.height", "y", y);
             return hm.height(x, y);
           },
           "x"_a, "y"_a, "Bilinear height [m].")
      .def("normal",
           [](const HeightMap& hm, double x, double y) {
             ernest::require_finite("HeightMap.normal", "x", x);
             ernest::require_finite("HeightMap.normal", "y", y);
             return hm.normal(x, y);
           },
           "x"_a, "y"_a, "Unit upward normal of the surface.")
      .def(
          "height_normal",
          [](const HeightMap& m, double x, double y) {
            ernest::require_finite("HeightMap.height_normal", "x", x);
            ernest::require_finite("HeightMap.height_normal", "y", y);
            Eigen::Vector3d n;
            const double h = m.height_normal(x, y, n);
            return py::make_tuple(h, n);
          },
          "x"_a, "y"_a, "(height [m], unit upward normal) in one query.")
      .def_property_readonly("heights", &HeightMap::heights)
      .def_property_readonly("spacing", &HeightMap::spacing)
      .def_property_readonly("origin_x", &HeightMap::origin_x)
      .def_property_readonly("origin_y", &HeightMap::origin_y);

  py::class_<BoxObstacle>(m, "BoxObstacle", "Rigid box: centre, full size, yaw/pitch/roll [rad].")
      .def(py::init([](const Eigen::Vector3d& centre, const Eigen::Vector3d& size, double yaw,
                       double pitch, double roll) {
             BoxObstacle b{centre, size, yaw, pitch, roll};
             b.validate();
             return b;
           }),
           "centre"_a, "size"_a, "yaw"_a = 0.0, "pitch"_a = 0.0, "roll"_a = 0.0)
      .def_readwrite("centre", &BoxObstacle::centre)
      .def_readwrite("size", &BoxObstacle::size)
      .def_readwrite("yaw", &BoxObstacle::yaw)
      .def_readwrite("pitch", &BoxObstacle::pitch)
      .def_readwrite("roll", &BoxObstacle::roll);

  py::enum_<GroundType>(m, "GroundType", "Soft soil (Bekker–Wong) or rigid ground (§3.4).")
      .value("Soil", GroundType::Soil)
      .value("Rigid", GroundType::Rigid);
  py::enum_<Stepper>(m, "Stepper",
                     "Who steps the rover's bodies: ODE's dWorldStep, or our own island step "
                     "(the same step to rounding, faster)")
      .value("Ode", Stepper::Ode)
      .value("Own", Stepper::Own);
  py::enum_<WheelObstacleContact>(m, "WheelObstacleContact",
                                  "How a wheel's contact with a rock is found: ODE's "
                                  "cylinder-box collider merged into one contact, or the exact "
                                  "penetration depth and normal (cylinder_box.hpp)")
      .value("Ode", WheelObstacleContact::Ode)
      .value("Exact", WheelObstacleContact::Exact);
  py::enum_<ActuatorMode>(m, "ActuatorMode", "Velocity servo, torque command, or unpowered.")
      .value("Velocity", ActuatorMode::Velocity)
      .value("Torque", ActuatorMode::Torque)
      .value("Off", ActuatorMode::Off);
  py::enum_<ClutchState>(m, "ClutchState", "Roll clutch state (§2.2).")
      .value("Disengaged", ClutchState::Disengaged)
      .value("Aligning", ClutchState::Aligning)
      .value("Engaged", ClutchState::Engaged);

  py::class_<SimOptions>(m, "SimOptions", "Simulation options (step, soil, rigid contact, seed).")
      .def(py::init<>())
      .def_readwrite("dt", &SimOptions::dt, "physics step [s] (default from the step study)")
      .def_readwrite("seed", &SimOptions::seed, "seeds the friction draw (std::mt19937_64)")
      .def_readwrite("ground", &SimOptions::ground)
      .def_readwrite("soil", &SimOptions::soil, "ernest_cpp.soil.SoilParameters")
      .def_readwrite("soil_points_per_panel", &SimOptions::soil_points_per_panel)
      .def_readwrite("soil_normal_damping", &SimOptions::soil_normal_damping,
                     "soil normal damping [N s/m per wheel]: F_n = max(0, F_z - c v_n) (assumption)")
      .def_readwrite("rigid", &SimOptions::rigid, "ernest_cpp.soil.RigidContactParameters")
      // a set value must be a real coefficient, checked when set (and by validate())
      .def_property(
          "friction", [](const SimOptions& o) { return o.friction; },
          [](SimOptions& o, std::optional<double> mu) {
            if (mu) ernest::require_in_range("SimOptions", "friction", *mu, 0.0, 10.0);
            o.friction = mu;
          },
          "Coulomb friction of the obstacles and rigid ground, [0, 10]; None (default) draws it "
          "from rigid with the seed")
      .def_readwrite("rigid_slip", &SimOptions::rigid_slip,
                     "tyre creep on rigid obstacles [(m/s)/N] (assumption)")
      .def_readwrite("rigid_tyre_stiffness_x", &SimOptions::rigid_tyre_stiffness_x,
                     "tyre stiffness along the rolling direction on rigid ground [N/m] (assumption)")
      .def_readwrite("rigid_tyre_stiffness_y", &SimOptions::rigid_tyre_stiffness_y,
                     "tyre stiffness along the axle on rigid ground [N/m] (assumption)")
      .def_readwrite("rigid_tyre_damping", &SimOptions::rigid_tyre_damping,
                     "tyre tangential damping on rigid ground [N s/m] (assumption)")
      .def_readwrite("guess_active_set", &SimOptions::guess_active_set,
                     "guess the bounded rows' active set from the last step and verify it (same "
                     "solution, ~3x faster on soil); False always pivots in ODE's LCP")
      .def_readwrite("guess_obstacle_contacts", &SimOptions::guess_obstacle_contacts,
                     "guess obstacle contacts sticking (friction rows unbounded, checked against "
                     "mu F_n after the step; the sparse solver's path); False: always with "
                     "their friction bounds (ODE's pivoting)")
      .def_readwrite("sparse_lcp", &SimOptions::sparse_lcp,
                     "solve steps whose rows are unbounded or have a zero bound (contact "
                     "normals) by a sparse LDL^T (minimum-degree order) instead of ODE's dense "
                     "solver (same solution to rounding); False: ODE's solver for every step")
      .def_readwrite("stepper", &SimOptions::stepper,
                     "Stepper.Ode: ODE's dWorldStep; Stepper.Own: our own island step "
                     "(cpp/solver/island_step.hpp), the same step to ~1e-10, falling back to "
                     "dWorldStep where it does not reproduce it")
      .def_readwrite("wheel_obstacle_contact", &SimOptions::wheel_obstacle_contact,
                     "WheelObstacleContact.Ode (default): ODE's dCollideCylinderBox, its points "
                     "merged; WheelObstacleContact.Exact: a wheel's contact with a rock by the "
                     "exact separating-axis theorem of a cylinder and a box (depth, normal; the "
                     "point at the depth-weighted centre of the deepest features)")
      .def_readwrite("resolve_rhs_only", &SimOptions::resolve_rhs_only,
                     "Own stepper: a re-solve whose rows are the last attempt's (the implicit "
                     "slip's level-only solves) keeps its rows, A and LDL^T factor and solves a "
                     "new right-hand side; one that only moved the soil rows' caps keeps the "
                     "rows and A off its diagonal (the same bits); False rebuilds every attempt")
      .def_readwrite("max_speed", &SimOptions::max_speed, "divergence threshold [m/s]")
      .def_readwrite("max_angular_speed", &SimOptions::max_angular_speed, "[rad/s]")
      .def_readwrite("slip_force_tolerance", &SimOptions::slip_force_tolerance,
                     "implicit slip [N]: accepted change of the soil forces between the slip "
                     "used and eq 12's at the step's end; 1e9 = explicit (chatters)")
      .def_readwrite("slip_warm_start", &SimOptions::slip_warm_start,
                     "implicit slip's first guess from the last steps (soil-row levels "
                     "extrapolated, the last slip offset over eq 12); False: eq 12 at the step's "
                     "start and the last levels")
      .def_readwrite("obstacle_substeps", &SimOptions::obstacle_substeps,
                     "a step in which a wheel touches an obstacle is taken as this many substeps "
                     "of dt / n (the §3.4 contact is under-resolved at the default step); 1 = none")
      .def("validate", &SimOptions::validate, "Raise ValueError naming an invalid field.");

  py::class_<Commands>(m, "Commands",
                       "Actuator set-points, held until changed. Assign whole lists to the "
                       "array fields (c.wheel_speed = [...]); item assignment is not kept.")
      .def(py::init<>())
      .def_readwrite("wheel_speed", &Commands::wheel_speed, "4 wheel speeds [rad/s]")
      .def_readwrite("wheel_torque", &Commands::wheel_torque, "4 torques [N m] (Torque mode)")
      .def_readwrite("wheel_mode", &Commands::wheel_mode)
      .def_readwrite("yaw_rate", &Commands::yaw_rate, "psi_dot [rad/s]")
      .def_readwrite("roll_rate", &Commands::roll_rate, "phi_dot [rad/s]")
      .def_readwrite("yaw_torque", &Commands::yaw_torque, "[N m] (Torque mode)")
      .def_readwrite("roll_torque", &Commands::roll_torque, "[N m] (Torque mode)")
      .def_readwrite("yaw_mode", &Commands::yaw_mode)
      .def_readwrite("roll_mode", &Commands::roll_mode)
      .def_readwrite("gimbal_enabled", &Commands::gimbal_enabled, "False: AGS off, yaw brake on")
      .def_readwrite("clutch_engage", &Commands::clutch_engage, "request the roll clutch")
      .def("validate", &Commands::validate, "Raise ValueError on a non-finite set-point.");

  py::class_<RoverState>(m, "RoverState",
                         "Sensors and ground truth after the last step (arrays are copies).")
      .def_readonly("time", &RoverState::time)
      .def_readonly("position", &RoverState::position, "chassis frame origin, world [m]")
      .def_readonly("quaternion", &RoverState::quaternion, "(w, x, y, z)")
      .def_readonly("linear_velocity", &RoverState::linear_velocity, "world [m/s]")
      .def_readonly("angular_velocity", &RoverState::angular_velocity, "world [rad/s]")
      .def_readonly("body_linear_velocity", &RoverState::body_linear_velocity, "chassis frame")
      .def_readonly("body_angular_velocity", &RoverState::body_angular_velocity, "chassis frame")
      .def_readonly("roll", &RoverState::roll)
      .def_readonly("pitch", &RoverState::pitch)
      .def_readonly("yaw", &RoverState::yaw)
      .def_readonly("gimbal_yaw", &RoverState::gimbal_yaw, "psi [rad]")
      .def_readonly("gimbal_roll", &RoverState::gimbal_roll, "phi [rad]")
      .def_readonly("gimbal_yaw_rate", &RoverState::gimbal_yaw_rate)
      .def_readonly("gimbal_roll_rate", &RoverState::gimbal_roll_rate)
      .def_readonly("yaw_torque", &RoverState::yaw_torque, "[N m]")
      .def_readonly("roll_torque", &RoverState::roll_torque, "tau_phi [N m] (reward, eq 38)")
      .def_readonly("bogie_frame_angle", &RoverState::bogie_frame_angle)
      .def_readonly("clutch", &RoverState::clutch)
      .def_property_readonly("wheel_speed", [](const RoverState& s) { return arr(s.wheel_speed); })
      .def_property_readonly("wheel_torque", [](const RoverState& s) { return arr(s.wheel_torque); })
      .def_property_readonly("wheel_load", [](const RoverState& s) { return arr(s.wheel_load); })
      .def_property_readonly("sinkage", [](const RoverState& s) { return arr(s.sinkage); })
      .def_property_readonly("slip", [](const RoverState& s) { return arr(s.slip); })
      .def_property_readonly("contact_vx", [](const RoverState& s) { return arr(s.contact_vx); })
      .def_property_readonly("contact_vy", [](const RoverState& s) { return arr(s.contact_vy); })
      .def_property_readonly("motor_current", [](const RoverState& s) { return arr(s.motor_current); })
      .def_property_readonly("motor_power", [](const RoverState& s) { return arr(s.motor_power); })
      .def_property_readonly(
          "wheel_position",
          [](const RoverState& s) {
            RowMat o(4, 3);
            for (int i = 0; i < 4; ++i) o.row(i) = s.wheel_position[i].transpose();
            return o;
          },
          "4 x 3 wheel centres, world [m]")
      .def_property_readonly(
          "fts",
          [](const RoverState& s) {
            RowMat o(4, 6);
            for (int i = 0; i < 4; ++i) o.row(i) = s.fts[i].transpose();
            return o;
          },
          "4 x 6 wrenches (Fx, Fy, Fz, Tx, Ty, Tz) on the mounts, sensor frames")
      .def_readonly("energy", &RoverState::energy, "electrical energy [J]");

  py::class_<SolverStats>(m, "SolverStats", "How RoverSim's active-set guesses fared.")
      .def_readonly("steps", &SolverStats::steps, "physics steps since construction")
      .def_readonly("first_guess", &SolverStats::first_guess, "steps whose first guess held")
      .def_readonly("later_guess", &SolverStats::later_guess, "steps held at a later guess")
      .def_readonly("pivoted", &SolverStats::pivoted, "steps where ODE pivoted the rows whose guesses kept failing")
      .def_readonly("lcp_errors", &SolverStats::lcp_errors,
                    "steps on which ODE's pivoting LCP reported an internal error")
      .def_readonly("sparse_solves", &SolverStats::sparse_solves,
                    "constraint solves (one per attempt at a step) done by the sparse LDL^T")
      .def_readonly("dense_solves", &SolverStats::dense_solves,
                    "constraint solves handed to ODE's Dantzig solver")
      .def_readonly("slip_solves", &SolverStats::slip_solves,
                    "extra solves of a step that made its slip agree with eq 12 at its end")
      .def_readonly("slip_driving", &SolverStats::slip_driving,
                    "steps with a wheel whose slip drove its motion (slip from the step's start)")
      .def_readonly("obstacle_guessed", &SolverStats::obstacle_guessed,
                    "steps (substeps) with obstacle contacts all solved sticking (sparse path)")
      .def_readonly("obstacle_bounded", &SolverStats::obstacle_bounded,
                    "steps (substeps) with an obstacle contact solved with its friction bounds")
      .def_readonly("obstacle_explicit", &SolverStats::obstacle_explicit,
                    "obstacle contacts (per step or substep) whose spring was integrated explicitly")
      .def_readonly("obstacle_implicit", &SolverStats::obstacle_implicit,
                    "obstacle contacts (per step or substep) whose spring was integrated implicitly "
                    "(effective mass too light for the explicit spring at the step)")
      .def_readonly("own_steps", &SolverStats::own_steps,
                    "attempts stepped by our own island step (SimOptions.stepper = Own)")
      .def_readonly("own_fallbacks", &SolverStats::own_fallbacks,
                    "attempts our own island step handed to ODE's dWorldStep")
      .def_readonly("rhs_resolves", &SolverStats::rhs_resolves,
                    "own steps solved as a new right-hand side of the last attempt's rows and "
                    "factor (SimOptions.resolve_rhs_only)")
      .def_readonly("cap_resolves", &SolverStats::cap_resolves,
                    "own steps that kept the last attempt's rows with new bounds and CFMs (A's "
                    "diagonal), factorised again (SimOptions.resolve_rhs_only)")
      .def_readonly("plans_made", &SolverStats::plans_made,
                    "sparse solves' symbolic analyses for row sets not remembered")
      .def_readonly("plans_grown", &SolverStats::plans_grown,
                    "remembered plans analysed again, grown by a pattern outside their factor")
      .def_readonly("obstacles_touched", &SolverStats::obstacles_touched,
                    "distinct obstacles in contact at the start of the last step")
      .def_readonly("fast_lcp", &SolverStats::fast_lcp,
                    "solves can take the sparse path: SimOptions.sparse_lcp, and the own island "
                    "step (SimOptions.stepper = Own) or the solver hook works in this process "
                    "(fast_lcp_active()); False: all are ODE's")
      .def("__repr__", [](const SolverStats& s) {
        return "SolverStats(steps=" + std::to_string(s.steps) + ", first_guess=" +
               std::to_string(s.first_guess) + ", later_guess=" + std::to_string(s.later_guess) +
               ", pivoted=" + std::to_string(s.pivoted) + ", lcp_errors=" +
               std::to_string(s.lcp_errors) + ", sparse_solves=" +
               std::to_string(s.sparse_solves) + ", dense_solves=" +
               std::to_string(s.dense_solves) + ", slip_solves=" +
               std::to_string(s.slip_solves) + ", slip_driving=" +
               std::to_string(s.slip_driving) + ", obstacle_guessed=" +
               std::to_string(s.obstacle_guessed) + ", obstacle_bounded=" +
               std::to_string(s.obstacle_bounded) + ", obstacle_explicit=" +
               std::to_string(s.obstacle_explicit) + ", obstacle_implicit=" +
               std::to_string(s.obstacle_implicit) + ", own_steps=" +
               std::to_string(s.own_steps) + ", own_fallbacks=" +
               std::to_string(s.own_fallbacks) + ", rhs_resolves=" +
               std::to_string(s.rhs_resolves) + ", cap_resolves=" +
               std::to_string(s.cap_resolves) + ", plans_made=" +
               std::to_string(s.plans_made) + ", plans_grown=" +
               std::to_string(s.plans_grown) + ", fast_lcp=" +
               (s.fast_lcp ? "True" : "False") + ")";
      });

  py::class_<Snapshot>(m, "Snapshot", "Complete simulation state for RoverSim.restore().")
      .def_property_readonly("time", [](const Snapshot& s) { return s.state.time; },
                             "Simulation time of the snapshot [s].")
      .def_property_readonly("state", [](const Snapshot& s) { return s.state; },
                             "The rover's state when the snapshot was taken (a copy of RoverState, "
                             "the same type as RoverSim.state).")
      .def_property_readonly("commands", [](const Snapshot& s) { return s.commands; },
                             "The actuator set-points held when the snapshot was taken (a copy).");

  py::class_<RoverSim, std::shared_ptr<RoverSim>>(
      m, "RoverSim",
      "ERNEST on ODE: chassis, Active Gimbal Suspension with roll clutch, bogie, four driven "
      "wheels on Bekker–Wong soil or rigid ground, rigid boxes (seed 004 §2–3).\n\n"
      "Threads: one thread at a time per RoverSim. A call made while another thread is inside "
      "one (e.g. step_n, which releases the GIL) raises RuntimeError instead of waiting; use one "
      "RoverSim per thread or a lock. After an ODE internal error (SimulationDiverged) the "
      "simulator refuses further steps, reset and restore: create a new one.")
      .def(py::init<const RoverParameters&, const HeightMap&, const std::vector<BoxObstacle>&,
                    const SimOptions&>(),
           "params"_a, "terrain"_a, "obstacles"_a = std::vector<BoxObstacle>{},
           "options"_a = SimOptions{})
      .def("reset", &RoverSim::reset, "x"_a, "y"_a, "heading"_a, "psi"_a = 0.0, "phi"_a = 0.0,
           "speed"_a = 0.0,
           "Place the rover on the terrain at rest (or rolling at speed [m/s]).")
      .def("set_commands", &RoverSim::set_commands, "commands"_a, "Set actuator set-points.")
      .def_property_readonly("commands", &RoverSim::commands)
      .def("step", &RoverSim::step, py::call_guard<py::gil_scoped_release>(),
           "One physics step; raises SimulationDiverged on a non-finite or absurd state.")
      .def("step_n", &RoverSim::step_n, "n"_a,
           py::call_guard<py::gil_scoped_release, interruptible>(),
           "n physics steps without returning to Python. Ctrl-C stops it between two steps "
           "(KeyboardInterrupt); the simulator stays usable.")
      .def_property_readonly("state", &RoverSim::state_copy,
                             "RoverState after the last step (a copy).")
      .def(
          "state_vector",
          [](const RoverSim& s) {
            py::array_t<double> o(RoverSim::kStateVectorSize);
            s.state_vector(o.mutable_data());
            return o;
          },
          "The state as STATE_VECTOR_SIZE values (a flat RoverState); names in "
          "state_vector_names(). Not the policy's observation (sensing.OBSERVATION_SIZE).")
      .def_static("state_vector_names", &RoverSim::state_vector_names,
                  "Names of the STATE_VECTOR_SIZE entries of state_vector().")
      .def("snapshot", &RoverSim::snapshot, "Full state; restore() reproduces runs bit for bit.")
      .def("restore", &RoverSim::restore, "snapshot"_a)
      .def("apply_chassis_force", &RoverSim::apply_chassis_force, "force"_a,
           "External force [N] on the chassis during the next step only.")
      .def("kinetic_energy", &RoverSim::kinetic_energy)
      .def("potential_energy", &RoverSim::potential_energy)
      .def_property_readonly("solver_stats",
                             [](const RoverSim& s) { return SolverStats(s.solver_stats()); },
                             "Counters of the active-set guesses (a copy).")
      .def_property_readonly("friction", &RoverSim::friction)
      .def_property_readonly("parameters", &RoverSim::parameters)
      .def_property_readonly("options", &RoverSim::options)
      .def_property_readonly("terrain", &RoverSim::terrain);
  m.attr("STATE_VECTOR_SIZE") = RoverSim::kStateVectorSize;
  m.attr("COMMAND_SIZE") = RoverSim::kCommandSize;

  py::class_<BatchStepper>(m, "BatchStepper",
                           "N independent rovers stepped on a thread pool; one call per batch "
                           "step, GIL released, numpy in and out.")
      .def(py::init<std::vector<std::shared_ptr<RoverSim>>, int>(), "sims"_a, "threads"_a = 1)
      .def(
          "step",
          [](BatchStepper& b, py::object commands, int n_steps) {
            const py::ssize_t n = b.size();
            py::array_t<double, py::array::c_style | py::array::forcecast> cmd;
            const double* cptr = nullptr;
            if (!commands.is_none()) {
              cmd = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(commands);
              if (!cmd || cmd.ndim() != 2 || cmd.shape(0) != n ||
                  cmd.shape(1) != RoverSim::kCommandSize)
                throw py::value_error("BatchStepper.step: commands must have shape (" +
                                      std::to_string(n) + ", " +
                                      std::to_string(RoverSim::kCommandSize) + ")");
              cptr = cmd.data();
            }
            py::array_t<double> states({n, static_cast<py::ssize_t>(RoverSim::kStateVectorSize)});
            double* sptr = states.mutable_data();
            {
              py::gil_scoped_release release;
              interruptible scope;  // Ctrl-C: every rover stops after a whole step
              b.step(cptr, n_steps, sptr);
            }
            return states;
          },
          "commands"_a, "n_steps"_a = 1,
          "commands: (N, 8) rows (w_FL, w_FR, w_RL, w_RR, psi_dot, phi_dot, gimbal_enabled, "
          "clutch_engage) or None to keep them; steps every rover n_steps times; returns the "
          "(N, STATE_VECTOR_SIZE) state vectors (RoverSim.state_vector()).")
      .def_property_readonly("size", &BatchStepper::size)
      .def_property_readonly("threads", &BatchStepper::threads)
      .def("sim", &BatchStepper::sim_ptr, "i"_a, "The i-th RoverSim.");

  py::class_<WheelSyncResult>(m, "WheelSyncResult", "Solution of eqs 4–10.")
      .def_readonly("x", &WheelSyncResult::x, "eq 5 (Vy, Vz, wz, v1x, v1z, ..., v4x, v4z)")
      .def_property_readonly("wheel_speeds", [](const WheelSyncResult& r) { return arr(r.wheel_speeds); },
                             "eq 10 [rad/s], FL, FR, RL, RR")
      .def_readonly("residual", &WheelSyncResult::residual, "||A x - y||")
      .def_readonly("A", &WheelSyncResult::A, "eq 6")
      .def_readonly("y", &WheelSyncResult::y, "eq 8");
  m.def("wheel_jacobian",
        [](const RoverParameters& p, double psi, double phi, int wheel) {
          p.validate();  // e.g. wheel_radius 0 would give NaN
          return wheel_jacobian(p, psi, phi, wheel);
        },
        "p"_a, "psi"_a, "phi"_a, "wheel"_a,
        "3 x 8 Jacobian J_i of eqs 1–2 (wheel frame; q_dot of eq 3).");
  m.def("synchronise_wheels",
        [](const RoverParameters& p, double psi, double phi, double vx, double wx, double wy,
           double psi_dot, double phi_dot) {
          p.validate();  // wheel_radius 0 gave NaN wheel speeds
          return synchronise_wheels(p, psi, phi, vx, wx, wy, psi_dot, phi_dot);
        },
        "p"_a, "psi"_a, "phi"_a, "vx"_a, "wx"_a,
        "wy"_a, "psi_dot"_a, "phi_dot"_a,
        "Wheel synchroniser of §2.3: wheel speeds (eq 10) from (Vx, wx, wy, psi_dot, phi_dot) "
        "at gimbal angles (psi, phi), with x = A^+ y (eq 9).");
  // The solver hook (ARCHITECTURE.md, "The solver hook"); ernest_cpp.dynamics wraps these and
  // turns an inactive hook into one RuntimeWarning.
  m.def("fast_lcp_active", &solver::fast_lcp_active,
        "Whether ODE's constraint solves reach ernest's sparse solver in this process (the "
        "symbol-binding hook of cpp/solver/ode_lcp.cpp works and answers a probe step as ODE "
        "does). False: every solve is ODE's Dantzig solver (slower; friction by ODE's "
        "approximation, not corrected to the final normal force). Initialises "
        "ODE; probes once per process.");
  m.def("fast_lcp_inactive_reason", &solver::fast_lcp_inactive_reason,
        "Why fast_lcp_active() is False; '' when it is True.");
}

}  // namespace ernest::bindings
