// Python bindings of cpp/opt (seed 000 gait transitions). Argument names equal the C++ names.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>

#include "bindings.hpp"
#include "ernest/common/validation.hpp"
#include "ernest/opt/asterix_model.hpp"
#include "ernest/opt/gait.hpp"
#include "ernest/opt/metrics.hpp"
#include "ernest/opt/nlopt_solver.hpp"
#include "ernest/opt/transition.hpp"
#include "interrupt.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::opt;

namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// A Python steering(t) -> (theta, theta_rate) as the C++ SteeringFunction of the kinematics.
SteeringFunction steering_from_python(py::function steering) {
  return [steering](double t, double& th, double& rate) {
    py::tuple out = steering(t);
    th = out[0].cast<double>();
    rate = out[1].cast<double>();
  };
}

// Samples of a (joint, time) -> (q, dq, ddq) function as three (len(times), joints) arrays.
// NaN or inf times raise ValueError naming `what` (they used to give NaN or zeros).
template <class F>
py::tuple sample_joints(const char* owner, const char* arg, int joints,
                        const Eigen::VectorXd& times, F&& f) {
  for (Eigen::Index k = 0; k < times.size(); ++k)
    ernest::require_finite(owner, (arg + ("[" + std::to_string(k) + "]")).c_str(), times[k]);
  RowMatrix q(times.size(), joints), dq(times.size(), joints), ddq(times.size(), joints);
  {
    py::gil_scoped_release release;
    for (Eigen::Index k = 0; k < times.size(); ++k)
      for (int j = 0; j < joints; ++j) f(j, times[k], q(k, j), dq(k, j), ddq(k, j));
  }
  return py::make_tuple(q, dq, ddq);
}

constexpr int kMaxConstraintRows = 100000;  // per constraint function (minimize_slsqp)

// A callback's result as (first, second), or ValueError naming the callback and what it returns.
std::pair<py::object, py::object> unpack2(const py::object& out, const std::string& what) {
  if (!py::isinstance<py::sequence>(out) || py::isinstance<py::str>(out) || py::len(out) != 2)
    throw std::invalid_argument(what + ", got " + py::repr(out).cast<std::string>());
  const auto seq = py::reinterpret_borrow<py::sequence>(out);
  return {seq[0], seq[1]};
}

// One returned item cast to T, or ValueError naming it (instead of pybind's "Unable to cast").
template <class T>
T cast_item(const py::object& item, const std::string& what) {
  try {
    return item.cast<T>();
  } catch (const py::cast_error&) {
    throw std::invalid_argument(what + ", got " + py::repr(item).cast<std::string>());
  }
}

// NaN or inf from a callback stops the run with ValueError (NLopt would otherwise end quietly).
template <class V>
void require_finite_output(const V& v, const std::string& what) {
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (!std::isfinite(v.data()[i]))
      throw std::invalid_argument(what + " has a non-finite entry (" + std::to_string(v.data()[i]) +
                                  " at index " + std::to_string(i) + ")");
}

// A Python callable fun(x) -> (values, jacobian) as a C++ ConstraintFunction. Called with the GIL
// held (minimize_slsqp keeps it for Python callbacks); errors propagate as py::error_already_set,
// which the solver captures and rethrows after NLopt returns.
ConstraintFunction wrap_constraint(py::function fun, int m, int n) {
  return [fun, m, n](const double* x, double* c, double* jac) {
    py::array_t<double> xa(n, x);
    const auto out =
        unpack2(fun(xa), "minimize_slsqp: a constraint fun(x) must return (values, jacobian)");
    auto values = cast_item<Eigen::VectorXd>(
        out.first, "minimize_slsqp: constraint values must be a sequence of m floats");
    if (values.size() != m) throw std::invalid_argument("constraint returned the wrong number of values");
    require_finite_output(values, "minimize_slsqp: constraint values");
    for (int i = 0; i < m; ++i) c[i] = values[i];
    if (jac) {
      auto J = cast_item<RowMatrix>(
          out.second, "minimize_slsqp: a constraint jacobian must be an (m, n) array");
      if (J.rows() != m || J.cols() != n)
        throw std::invalid_argument("constraint jacobian must have shape (m, n)");
      require_finite_output(J, "minimize_slsqp: constraint jacobian");
      for (int i = 0; i < m; ++i)
        for (int k = 0; k < n; ++k) jac[i * n + k] = J(i, k);
    }
  };
}

}  // namespace

void bind_opt(py::module_& m) {
  // ---- model and kinematics --------------------------------------------------------------
  py::class_<AsterixParameters>(m, "AsterixParameters",
                                "Asterix rover parameters (seed 000 §5; 7.8 kg from the paper, the "
                                "rest our documented choices, SI units).")
      .def(py::init<>())
      .def_readwrite("mass", &AsterixParameters::mass, "[kg] (paper)")
      .def_readwrite("wheel_radius", &AsterixParameters::wheel_radius, "R [m]")
      .def_readwrite("l_x", &AsterixParameters::l_x, "steering joint to axle [m] (eq 22)")
      .def_readwrite("half_track", &AsterixParameters::half_track, "[m]")
      .def_readwrite("forward_speed", &AsterixParameters::forward_speed, "V_r [m/s]")
      .def_readwrite("steering_limit", &AsterixParameters::steering_limit, "[rad]")
      .def_readwrite("roll_limit", &AsterixParameters::roll_limit, "[rad]")
      .def_readwrite("steering_velocity_limit", &AsterixParameters::steering_velocity_limit, "[rad/s]")
      .def_readwrite("roll_velocity_limit", &AsterixParameters::roll_velocity_limit, "[rad/s]")
      .def_readwrite("steering_acceleration_limit",
                     &AsterixParameters::steering_acceleration_limit, "[rad/s^2]")
      .def_readwrite("roll_acceleration_limit", &AsterixParameters::roll_acceleration_limit,
                     "[rad/s^2]")
      .def_readwrite("steering_inertia", &AsterixParameters::steering_inertia, "[kg m^2]")
      .def_readwrite("roll_inertia", &AsterixParameters::roll_inertia, "[kg m^2]")
      .def_readwrite("joint_viscous", &AsterixParameters::joint_viscous, "[N m s/rad]")
      .def_readwrite("joint_coulomb", &AsterixParameters::joint_coulomb, "[N m]")
      .def_readwrite("roll_stiffness", &AsterixParameters::roll_stiffness, "[N m/rad]")
      .def_readwrite("rolling_resistance", &AsterixParameters::rolling_resistance, "C_rr [-]")
      .def_readwrite("wheel_torque_constant", &AsterixParameters::wheel_torque_constant,
                     "k_t [N m/A] (paper)")
      .def_readwrite("gravity", &AsterixParameters::gravity, "[m/s^2]")
      .def("validate", &AsterixParameters::validate,
           "Raise ValueError naming the first field outside its allowed range.")
      .def("position_limit", &AsterixParameters::position_limit, "(steering, roll) [rad]")
      .def("velocity_limit", &AsterixParameters::velocity_limit, "(steering, roll) [rad/s]")
      .def("acceleration_limit", &AsterixParameters::acceleration_limit, "(steering, roll) [rad/s^2]");
  m.attr("STEERING") = kSteering;
  m.attr("ROLL") = kRoll;

  py::class_<Pose2>(m, "Pose2", "Planar pose (x, y, heading) of the wheel centroid.")
      .def(py::init<>())
      .def(py::init([](double x, double y, double heading) { return Pose2{x, y, heading}; }),
           "x"_a, "y"_a, "heading"_a)
      .def_readwrite("x", &Pose2::x)
      .def_readwrite("y", &Pose2::y)
      .def_readwrite("heading", &Pose2::heading);
  m.def("compose", &compose, "a"_a, "b"_a, "a ⊕ b.");
  m.def("relative", &relative, "a"_a, "b"_a, "a^-1 ⊕ b.");

  py::class_<IntegrationOptions>(m, "IntegrationOptions", "Adaptive Dormand–Prince tolerances.")
      .def(py::init<>())
      .def_readwrite("abs_tol", &IntegrationOptions::abs_tol)
      .def_readwrite("rel_tol", &IntegrationOptions::rel_tol)
      .def_readwrite("max_steps", &IntegrationOptions::max_steps)
      .def("validate", &IntegrationOptions::validate, "Raise ValueError on an invalid field.");

  py::register_exception<KinematicsError>(m, "KinematicsError", PyExc_RuntimeError);

  py::class_<AsterixKinematics>(m, "AsterixKinematics",
                                "Wheel kinematics of eqs 20–23 with synchronised (no-skid) wheels.")
      .def(py::init<const AsterixParameters&>(), "params"_a = AsterixParameters{})
      .def_property_readonly("params", &AsterixKinematics::params)
      .def("heading_rate", &AsterixKinematics::heading_rate, "theta"_a, "Eq 22 averaged [rad/s].")
      .def("wheel_yaw_rates", &AsterixKinematics::wheel_yaw_rates, "theta"_a, "theta_rate"_a,
           "Eq 22 per wheel (FL, FR, RL, RR).")
      .def("wheel_speeds", &AsterixKinematics::wheel_speeds, "theta"_a, "theta_rate"_a,
           "Synchronised wheel angular speeds (FL, FR, RL, RR) [rad/s].")
      .def("pose_rate",
           [](const AsterixKinematics& k, double psi, double theta, double theta_rate) {
             double dx, dy, dpsi;
             k.pose_rate(psi, theta, theta_rate, dx, dy, dpsi);
             if (!std::isfinite(dx) || !std::isfinite(dy) || !std::isfinite(dpsi))  // NaN in or overflow
               throw std::invalid_argument("AsterixKinematics.pose_rate: psi, theta, theta_rate = " +
                                           std::to_string(psi) + ", " + std::to_string(theta) + ", " +
                                           std::to_string(theta_rate) + " give a rate that is not finite");
             return py::make_tuple(dx, dy, dpsi);
           },
           "psi"_a, "theta"_a, "theta_rate"_a, "(dx/dt, dy/dt, dpsi/dt) of the wheel centroid.")
      .def("turning_radius", &AsterixKinematics::turning_radius, "theta"_a,
           "Radius of the centroid's circle at constant steering [m]; inf at theta = 0 (a straight "
           "line).")
      .def("integrate",
           [](const AsterixKinematics& k, py::function steering, double t0, double t1,
              const Pose2& start, const IntegrationOptions& options) {
             return k.integrate(steering_from_python(steering), t0, t1, start, options);
           },
           "steering"_a, "t0"_a, "t1"_a, "start"_a = Pose2{}, "options"_a = IntegrationOptions{},
           "Pose at t1 for steering(t) -> (theta, theta_rate); KinematicsError on no progress.")
      .def("integrate_wheels",
           [](const AsterixKinematics& k, py::function steering, double t0, double t1,
              const Pose2& start, const IntegrationOptions& options) {
             return k.integrate_wheels(steering_from_python(steering), t0, t1, start, options);
           },
           "steering"_a, "t0"_a, "t1"_a, "start"_a = Pose2{}, "options"_a = IntegrationOptions{},
           "Per-wheel states (x_i, y_i, beta_i) of eqs 20–22 at t1.")
      .def("wheel_states", &AsterixKinematics::wheel_states, "pose"_a, "theta"_a,
           "Rigid-geometry wheel positions and yaws for a pose and steering angle.")
      .def_static("pose_from_wheels", &AsterixKinematics::pose_from_wheels, "wheels"_a,
                  "Eq 23: mean wheel position and yaw.");

  // ---- gaits ---------------------------------------------------------------------------------
  py::class_<Gait>(m, "Gait",
                   "Periodic gait (eq 1): q_j(t) = offset_j + amplitude_j sin(2 pi t / period + phase_j).")
      .def(py::init<std::string, double, Eigen::VectorXd, Eigen::VectorXd, Eigen::VectorXd>(),
           "name"_a, "period"_a, "offset"_a, "amplitude"_a, "phase"_a)
      .def_property_readonly("name", &Gait::name)
      .def_property_readonly("period", &Gait::period)
      .def_property_readonly("joints", &Gait::joints)
      .def_property_readonly("offset", &Gait::offset)
      .def_property_readonly("amplitude", &Gait::amplitude)
      .def_property_readonly("phase", &Gait::phase)
      .def("position", &Gait::position, "t"_a, "Joint positions at phase t.")
      .def("velocity", &Gait::velocity, "t"_a, "Joint velocities at phase t.")
      .def("acceleration", &Gait::acceleration, "t"_a, "Joint accelerations at phase t.")
      .def("sample",
           [](const Gait& g, const Eigen::VectorXd& times) {
             return sample_joints("Gait.sample", "times", g.joints(), times,
                                  [&g](int j, double t, double& q, double& dq, double& ddq) {
                                    g.evaluate(j, t, q, dq, ddq);
                                  });
           },
           "times"_a, "(q, dq, ddq), each of shape (len(times), joints).")
      .def("check_limits", &Gait::check_limits, "position_limit"_a, "velocity_limit"_a,
           "Raise ValueError if the gait leaves the limits.")
      .def("__repr__", [](const Gait& g) {
        return "Gait('" + g.name() + "', period=" + format_number(g.period()) + " s)";
      });
  m.def("squirming", &squirming, "p"_a = AsterixParameters{}, "The squirming gait (Fig. 5).");
  m.def("wheel_walking", &wheel_walking, "p"_a = AsterixParameters{},
        "The wheel-walking gait (Fig. 6).");
  m.def("gait_pose",
        [](const AsterixKinematics& kin, const Gait& gait, double t_start, double t_end,
           const Pose2& start, const IntegrationOptions& options) {
          py::gil_scoped_release release;
          return gait_pose(kin, gait, t_start, t_end, start, options);
        },
        "kin"_a, "gait"_a, "t_start"_a, "t_end"_a, "start"_a = Pose2{},
        "options"_a = IntegrationOptions{}, "Workspace trajectory G(t) of a gait (eqs 6–7).");

  // ---- NLopt wrapper ----------------------------------------------------------------------------
  py::class_<SolverOptions>(m, "SolverOptions", "SLSQP stopping criteria and time budget.")
      .def(py::init<>())
      .def_readwrite("max_time", &SolverOptions::max_time, "[s] (paper: 0.5)")
      .def_readwrite("xtol_rel", &SolverOptions::xtol_rel)
      .def_readwrite("ftol_rel", &SolverOptions::ftol_rel)
      .def_readwrite("ftol_abs", &SolverOptions::ftol_abs)
      .def_readwrite("max_eval", &SolverOptions::max_eval)
      .def_readwrite("constraint_tol", &SolverOptions::constraint_tol)
      .def("validate", &SolverOptions::validate, "Raise ValueError on an invalid field.");

  py::class_<SolverResult>(m, "SolverResult", "Result of minimize_slsqp.")
      .def(py::init<>())
      .def_readonly("x", &SolverResult::x)
      .def_readonly("value", &SolverResult::value)
      .def_readonly("status", &SolverResult::status, "nlopt_result code")
      .def_readonly("status_name", &SolverResult::status_name)
      .def_readonly("evaluations", &SolverResult::evaluations)
      .def_readonly("seconds", &SolverResult::seconds)
      .def_property_readonly("converged", &SolverResult::converged)
      .def("__repr__", [](const SolverResult& r) {
        return "SolverResult(value=" + format_number(r.value) + ", status=" + r.status_name +
               ", evaluations=" + std::to_string(r.evaluations) + ")";
      });

  m.def("minimize_slsqp",
        [](py::function objective, const std::vector<double>& x0, std::vector<double> lower,
           std::vector<double> upper, const std::vector<std::pair<int, py::function>>& inequality,
           const std::vector<std::pair<int, py::function>>& equality, const SolverOptions& options) {
          const int n = static_cast<int>(x0.size());
          OptimizationProblem p;
          p.dimension = n;
          p.lower = std::move(lower);
          p.upper = std::move(upper);
          p.objective = [objective, n](const double* x, double* grad) {
            py::array_t<double> xa(n, x);
            const auto out = unpack2(objective(xa),
                                     "minimize_slsqp: objective(x) must return (value, gradient)");
            const double value = cast_item<double>(
                out.first, "minimize_slsqp: the objective's value must be a float");
            ernest::require(std::isfinite(value),
                            "minimize_slsqp: objective(x) returned a non-finite value (" +
                                std::to_string(value) + ")");
            if (grad) {
              auto g = cast_item<Eigen::VectorXd>(
                  out.second,
                  "minimize_slsqp: the objective's gradient must be a sequence of len(x0) floats");
              if (g.size() != n) throw std::invalid_argument("gradient must have len(x0) entries");
              require_finite_output(g, "minimize_slsqp: the objective's gradient");
              for (int i = 0; i < n; ++i) grad[i] = g[i];
            }
            return value;
          };
          // m rows of n values each are allocated per constraint: bound m before NLopt does
          for (const auto* set : {&inequality, &equality})
            for (const auto& c : *set)
              ernest::require_in_range("minimize_slsqp",
                                       set == &inequality ? "inequality m" : "equality m", c.first,
                                       0, kMaxConstraintRows);
          for (const auto& c : inequality) p.inequality.push_back({c.first, wrap_constraint(c.second, c.first, n)});
          for (const auto& c : equality) p.equality.push_back({c.first, wrap_constraint(c.second, c.first, n)});
          // The GIL stays held: the callbacks are Python. An exception raised in one is captured,
          // NLopt is stopped, and the same Python exception is re-raised here.
          return minimize_slsqp(p, x0, options);
        },
        "objective"_a, "x0"_a, "lower"_a = std::vector<double>{}, "upper"_a = std::vector<double>{},
        "inequality"_a = std::vector<std::pair<int, py::function>>{},
        "equality"_a = std::vector<std::pair<int, py::function>>{}, "options"_a = SolverOptions{},
        "NLopt SLSQP. objective(x) -> (value, gradient); each constraint is (m, fun) with "
        "fun(x) -> (values[m], jacobian[m, n]), feasible when values <= 0 (inequality) or == 0. "
        "An exception raised by a callback stops the run and is re-raised with its type.");
  m.def("nlopt_status_name", &nlopt_status_name, "status"_a, "Name of an nlopt_result code.");

  // ---- transitions ------------------------------------------------------------------------------
  py::enum_<Strategy>(m, "Strategy", "Transition strategies of seed 000 §4.")
      .value("Naive", Strategy::Naive)
      .value("Bezier", Strategy::Bezier)
      .value("Linear", Strategy::Linear)
      .value("Spline", Strategy::Spline);
  py::enum_<WeightSet>(m, "WeightSet", "Table 1 weight distributions.")
      .value("Duration", WeightSet::Duration)
      .value("Deviation", WeightSet::Deviation)
      .value("Balanced", WeightSet::Balanced);
  m.def("strategy_from_string", &strategy_from_string, "name"_a,
        "'naive', 'bezier', 'linear' or 'spline'.");
  m.def("weight_set_from_string", &weight_set_from_string, "name"_a,
        "'duration', 'deviation' or 'balanced'.");
  m.def("strategy_name", [](Strategy s) { return to_string(s); }, "s"_a, "Lower-case name.");
  m.def("weight_set_name", [](WeightSet w) { return to_string(w); }, "w"_a, "Lower-case name.");

  py::class_<CostWeights>(m, "CostWeights", "Weights of eq 8 (+ the eq 19 linear cost).")
      .def(py::init<>())
      .def(py::init([](double duration, double acceleration, double deviation, double linear) {
             return CostWeights{duration, acceleration, deviation, linear};
           }),
           "duration"_a, "acceleration"_a, "deviation"_a, "linear"_a = 1.0)
      .def_readwrite("duration", &CostWeights::duration, "w1")
      .def_readwrite("acceleration", &CostWeights::acceleration, "w2")
      .def_readwrite("deviation", &CostWeights::deviation, "w3")
      .def_readwrite("linear", &CostWeights::linear, "weight of eq 19 (Linear only)")
      .def("validate", &CostWeights::validate, "Raise ValueError on an invalid field.")
      .def_static("table1", &CostWeights::table1, "strategy"_a, "set"_a, "Table 1 of seed 000.");

  py::class_<TransitionOptions>(m, "TransitionOptions",
                                "Options of the optimised strategies (normalisations of eq 8).")
      .def(py::init<>())
      .def_readwrite("solver", &TransitionOptions::solver)
      .def_readwrite("waypoints", &TransitionOptions::waypoints)
      .def_readwrite("min_duration", &TransitionOptions::min_duration)
      .def_readwrite("max_duration", &TransitionOptions::max_duration)
      .def_readwrite("duration_scale", &TransitionOptions::duration_scale)
      .def_readwrite("acceleration_scale", &TransitionOptions::acceleration_scale)
      .def_readwrite("position_scale", &TransitionOptions::position_scale)
      .def_readwrite("heading_scale", &TransitionOptions::heading_scale)
      .def_readwrite("linear_scale", &TransitionOptions::linear_scale)
      .def_readwrite("initial_durations", &TransitionOptions::initial_durations)
      .def_readwrite("initial_phases", &TransitionOptions::initial_phases)
      .def_readwrite("limit_margin", &TransitionOptions::limit_margin)
      .def_readwrite("feasibility_tol", &TransitionOptions::feasibility_tol)
      .def_readwrite("fallback", &TransitionOptions::fallback)
      .def_readwrite("integration", &TransitionOptions::integration)
      .def("validate", &TransitionOptions::validate, "Raise ValueError on an invalid field.");

  py::class_<TransitionProblem>(m, "TransitionProblem",
                                "A transition from gait `from_gait` at t1 to gait `to_gait`.")
      .def(py::init<const AsterixParameters&, Gait, Gait, double>(), "rover"_a, "from_gait"_a,
           "to_gait"_a, "t1"_a)
      .def(py::init<const AsterixParameters&, Gait, Gait, double, Eigen::VectorXd, Eigen::VectorXd,
                    Eigen::VectorXd>(),
           "rover"_a, "from_gait"_a, "to_gait"_a, "t1"_a, "position_limit"_a, "velocity_limit"_a,
           "acceleration_limit"_a)
      .def_readonly("rover", &TransitionProblem::rover)
      .def_readonly("from_gait", &TransitionProblem::from)
      .def_readonly("to_gait", &TransitionProblem::to)
      .def_readonly("t1", &TransitionProblem::t1)
      .def_readonly("position_limit", &TransitionProblem::position_limit)
      .def_readonly("velocity_limit", &TransitionProblem::velocity_limit)
      .def_readonly("acceleration_limit", &TransitionProblem::acceleration_limit)
      .def_property_readonly("joints", &TransitionProblem::joints);

  py::class_<TransitionResult>(m, "TransitionResult", "A planned transition.")
      .def_readonly("requested", &TransitionResult::requested)
      .def_readonly("strategy", &TransitionResult::strategy)
      .def_readonly("weights", &TransitionResult::weights)
      .def_readonly("fell_back", &TransitionResult::fell_back)
      .def_readonly("fallback_reason", &TransitionResult::fallback_reason)
      .def_readonly("t1", &TransitionResult::t1)
      .def_readonly("duration", &TransitionResult::duration, "T [s]")
      .def_readonly("phase_shift", &TransitionResult::phase_shift, "phi of eq 3 [s]")
      .def_readonly("end_phase", &TransitionResult::end_phase, "t1 + T - phi [s]")
      .def_readonly("solver", &TransitionResult::solver)
      .def_readonly("seconds", &TransitionResult::seconds, "total planning time [s]")
      .def_readonly("cost", &TransitionResult::cost)
      .def_readonly("cost_duration", &TransitionResult::cost_duration)
      .def_readonly("cost_acceleration", &TransitionResult::cost_acceleration)
      .def_readonly("cost_deviation", &TransitionResult::cost_deviation)
      .def_readonly("cost_linear", &TransitionResult::cost_linear)
      .def_readonly("max_violation", &TransitionResult::max_violation)
      .def_property_readonly("joints", &TransitionResult::joints)
      .def_property_readonly("waypoints",
                             [](const TransitionResult& r) -> Eigen::MatrixXd {
                               if (r.strategy == Strategy::Naive) return Eigen::MatrixXd();
                               return r.spline.waypoints();
                             },
                             "Waypoints (joints x N) of Bezier/Linear/Spline; empty for Naive.")
      .def("sample",
           [](const TransitionResult& r, const Eigen::VectorXd& tau) {
             return sample_joints("TransitionResult.sample", "tau", r.joints(), tau,
                                  [&r](int j, double t, double& q, double& dq, double& ddq) {
                                    r.evaluate(j, t, q, dq, ddq);
                                  });
           },
           "tau"_a, "(q, dq, ddq) of the transition at tau in [0, T] after t1.")
      .def("peaks",
           [](const TransitionResult& r) {
             Eigen::VectorXd q(r.joints()), v(r.joints());
             for (int j = 0; j < r.joints(); ++j) r.peaks(j, q[j], v[j]);
             return py::make_tuple(q, v);
           },
           "(max |q|, max |dq/dt|) per joint over the transition, from the analytic extrema.")
      .def("sample_executed",
           [](const TransitionResult& r, const TransitionProblem& problem,
              const Eigen::VectorXd& times) {
             return sample_joints("TransitionResult.sample_executed", "times", r.joints(), times,
                                  [&](int j, double t, double& q, double& dq, double& ddq) {
                                    r.executed(problem, j, t, q, dq, ddq);
                                  });
           },
           "problem"_a, "times"_a, "(q, dq, ddq) of g1, then the transition, then g2(t - phi).");

  m.def("plan_transition",
        [](const TransitionProblem& problem, Strategy strategy, const CostWeights& weights,
           const TransitionOptions& options) {
          py::gil_scoped_release release;
          interruptible scope;  // Ctrl-C between SLSQP objective evaluations
          return plan_transition(problem, strategy, weights, options);
        },
        "problem"_a, "strategy"_a, "weights"_a = CostWeights{}, "options"_a = TransitionOptions{},
        "Plan one transition (releases the GIL). Failures fall back to Naive with the reason.");
  m.def("naive_transition", &naive_transition, "problem"_a, "The Naive transition.");
  m.def("transition_dimension", &transition_dimension, "problem"_a, "strategy"_a,
        "options"_a = TransitionOptions{}, "Size of x = [T, sigma, interior waypoints].");
  m.def("transition_cost",
        [](const TransitionProblem& problem, Strategy strategy, const CostWeights& weights,
           const TransitionOptions& options, const std::vector<double>& x) {
          std::vector<double> grad;
          double f;
          {
            py::gil_scoped_release release;
            f = transition_cost(problem, strategy, weights, options, x, &grad);
          }
          return py::make_tuple(f, Eigen::Map<Eigen::VectorXd>(grad.data(), grad.size()).eval());
        },
        "problem"_a, "strategy"_a, "weights"_a, "options"_a, "x"_a,
        "(cost eq 8, analytic gradient) at x.");
  m.def("transition_constraints",
        [](const TransitionProblem& problem, Strategy strategy, const TransitionOptions& options,
           const std::vector<double>& x) {
          std::vector<double> values, jac;
          {
            py::gil_scoped_release release;
            transition_constraints(problem, strategy, options, x, values, &jac);
          }
          const Eigen::Index mrows = static_cast<Eigen::Index>(values.size());
          const Eigen::Index ncols = static_cast<Eigen::Index>(x.size());
          RowMatrix J = Eigen::Map<RowMatrix>(jac.data(), mrows, ncols);
          return py::make_tuple(Eigen::Map<Eigen::VectorXd>(values.data(), mrows).eval(), J);
        },
        "problem"_a, "strategy"_a, "options"_a, "x"_a,
        "(values <= 0 when feasible, Jacobian) of the strategy's inequality constraints.");

  // ---- metrics ------------------------------------------------------------------------------------
  py::class_<MetricsOptions>(m, "MetricsOptions", "Sampling of the metrics.")
      .def(py::init<>())
      .def_readwrite("telemetry_rate", &MetricsOptions::telemetry_rate, "[Hz]")
      .def_readwrite("energy_step", &MetricsOptions::energy_step, "[s]")
      .def_readwrite("integration", &MetricsOptions::integration)
      .def("validate", &MetricsOptions::validate, "Raise ValueError on an invalid field.");

  py::class_<TransitionMetrics>(m, "TransitionMetrics", "Per-transition metrics (eqs 24–28).")
      .def_readonly("duration", &TransitionMetrics::duration)
      .def_readonly("max_acceleration", &TransitionMetrics::max_acceleration)
      .def_readonly("heading_change", &TransitionMetrics::heading_change)
      .def_readonly("heading_deviation", &TransitionMetrics::heading_deviation)
      .def_readonly("position_deviation", &TransitionMetrics::position_deviation)
      .def_readonly("distance", &TransitionMetrics::distance)
      .def_readonly("energy_articulation", &TransitionMetrics::energy_articulation)
      .def_readonly("energy_wheels", &TransitionMetrics::energy_wheels)
      .def_readonly("energy", &TransitionMetrics::energy)
      .def_readonly("cost_of_transport", &TransitionMetrics::cost_of_transport)
      .def_readonly("start_position_residual", &TransitionMetrics::start_position_residual)
      .def_readonly("start_velocity_residual", &TransitionMetrics::start_velocity_residual)
      .def_readonly("end_position_residual", &TransitionMetrics::end_position_residual)
      .def_readonly("end_velocity_residual", &TransitionMetrics::end_velocity_residual)
      .def_readonly("start_pose", &TransitionMetrics::start_pose)
      .def_readonly("end_pose", &TransitionMetrics::end_pose)
      .def_readonly("target_pose", &TransitionMetrics::target_pose);
  m.def("evaluate_metrics",
        [](const TransitionProblem& problem, const TransitionResult& result,
           const MetricsOptions& options) {
          py::gil_scoped_release release;
          return evaluate_metrics(problem, result, options);
        },
        "problem"_a, "result"_a, "options"_a = MetricsOptions{},
        "Metrics of one transition (releases the GIL).");
}

}  // namespace ernest::bindings
