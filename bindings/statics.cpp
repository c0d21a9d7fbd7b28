// Python bindings of cpp/statics (ERNEST's mass model and lift-off torque bind themselves in
// bindings/statics_rover.cpp, called from bind_statics). Argument names equal the C++ names. Point sets are (3, N)
// arrays as in C++ (one column per contact); a wrong shape or a NaN raises ValueError naming the
// argument or field.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "interrupt.hpp"
#include "ernest/statics/calibration.hpp"
#include "ernest/statics/force_distribution.hpp"
#include "ernest/statics/sag.hpp"
#include "ernest/statics/stability.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::statics;

namespace {

using Array = py::array_t<double, py::array::forcecast>;

std::string shape_of(const Array& a) {
  std::ostringstream os;
  os << "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) os << (i ? ", " : "") << a.shape(i);
  os << (a.ndim() == 1 ? ",)" : ")");
  return os.str();
}

// (3, N) array -> Matrix3Xd; ValueError naming `field` otherwise.
Eigen::Matrix3Xd points(const Array& a, const char* field) {
  if (a.ndim() != 2 || a.shape(0) != 3) {
    throw std::invalid_argument(std::string(field) + " must have shape (3, N), got " +
                                shape_of(a));
  }
  Eigen::Matrix3Xd m(3, a.shape(1));
  auto r = a.unchecked<2>();
  for (py::ssize_t j = 0; j < a.shape(1); ++j) {
    for (int i = 0; i < 3; ++i) m(i, j) = r(i, j);
  }
  return m;
}

Eigen::Vector3d vec3(const Array& a, const char* field) {
  if (a.ndim() != 1 || a.shape(0) != 3) {
    throw std::invalid_argument(std::string(field) + " must have shape (3,), got " + shape_of(a));
  }
  auto r = a.unchecked<1>();
  return {r(0), r(1), r(2)};
}

// A point a function computes with: NaN or inf is refused here (struct setters take any value and
// the solvers check it).
Eigen::Vector3d finite3(const Array& a, const char* field) {
  const Eigen::Vector3d v = vec3(a, field);
  if (!v.allFinite()) throw std::invalid_argument(std::string(field) + " must be finite");
  return v;
}

Eigen::VectorXd vecn(const Array& a, const char* field) {
  if (a.ndim() != 1) {
    throw std::invalid_argument(std::string(field) + " must be 1-D, got " + shape_of(a));
  }
  Eigen::VectorXd v(a.shape(0));
  auto r = a.unchecked<1>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i) v(i) = r(i);
  return v;
}

Eigen::Matrix3d mat3(const Array& a, const char* field) {
  if (a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) != 3) {
    throw std::invalid_argument(std::string(field) + " must have shape (3, 3), got " +
                                shape_of(a));
  }
  Eigen::Matrix3d m;
  auto r = a.unchecked<2>();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m(i, j) = r(i, j);
  }
  return m;
}

// def_property for a (3, N) / (3,) / (N,) / (3, 3) member with a shape-checking setter.
#define ERNEST_POINTS(cls, name, doc)                                                  \
  def_property(                                                                        \
      #name, [](const cls& s) { return s.name; },                                      \
      [](cls& s, const Array& a) { s.name = points(a, #cls "." #name); }, doc)
#define ERNEST_VEC3(cls, name, doc)                                                    \
  def_property(                                                                        \
      #name, [](const cls& s) { return s.name; },                                      \
      [](cls& s, const Array& a) { s.name = vec3(a, #cls "." #name); }, doc)
#define ERNEST_VECN(cls, name, doc)                                                    \
  def_property(                                                                        \
      #name, [](const cls& s) { return s.name; },                                      \
      [](cls& s, const Array& a) { s.name = vecn(a, #cls "." #name); }, doc)
#define ERNEST_MAT3(cls, name, doc)                                                    \
  def_property(                                                                        \
      #name, [](const cls& s) { return s.name; },                                      \
      [](cls& s, const Array& a) { s.name = mat3(a, #cls "." #name); }, doc)

void bind_stability(py::module_& m) {
  m.attr("MAX_CONTACTS") = kMaxContacts;
  py::class_<ProjectionFrame>(m, "ProjectionFrame",
                              "Orthonormal frame (e1, e2, up) with up = -g/|g|; polygons live "
                              "in its (e1, e2) plane.")
      .def(py::init<>())
      .def_readonly("up", &ProjectionFrame::up)
      .def_readonly("e1", &ProjectionFrame::e1)
      .def_readonly("e2", &ProjectionFrame::e2)
      .def_static(
          "from_gravity",
          [](const Array& gravity) { return ProjectionFrame::from_gravity(vec3(gravity, "gravity")); },
          "gravity"_a, "Frame for a gravity vector (g along -z gives the world x, y, z).")
      .def(
          "project",
          [](const ProjectionFrame& f, const Array& p) { return Eigen::Vector2d(f.project(vec3(p, "p"))); },
          "p"_a, "Coordinates of p projected along gravity onto the (e1, e2) plane.");

  py::class_<Polygon>(m, "Polygon",
                      "Convex polygon in a ProjectionFrame, counter-clockwise; size 2 is a "
                      "segment, 1 a point, 0 empty.")
      .def_readonly("size", &Polygon::size)
      .def_property_readonly("vertices", &Polygon::vertex_matrix, "(2, size) vertex coordinates")
      .def_property_readonly(
          "edge_contacts",
          [](const Polygon& p) {
            std::vector<std::pair<int, int>> e;
            for (int i = 0; i < p.size; ++i) e.emplace_back(p.edge_contacts[i][0], p.edge_contacts[i][1]);
            return e;
          },
          "for edge k (vertex k -> k+1) the two contacts whose line carries it")
      .def("area", &Polygon::area, "Area [m^2].")
      .def(
          "signed_distance",
          [](const Polygon& p, const Eigen::Vector2d& q) { return p.signed_distance(q); }, "q"_a,
          "Signed distance of q to the boundary: > 0 inside, < 0 outside, -inf if empty.");

  m.def(
      "support_polygon",
      [](const Array& contacts, const ProjectionFrame& frame) {
        return support_polygon(points(contacts, "contacts"), frame);
      },
      "contacts"_a, "frame"_a,
      "Convex hull of the contacts (3, N) projected along gravity (seed 003 §3.3).");
  m.def(
      "conservative_support_polygon",
      [](const Array& contacts, const ProjectionFrame& frame) {
        return conservative_support_polygon(points(contacts, "contacts"), frame);
      },
      "contacts"_a, "frame"_a,
      "Conservative Polygon of Support (§3.3): the intersection of the support polygons with "
      "each one contact removed. Empty for three contacts or fewer.");
  m.def(
      "nesm_edge",
      [](const Array& a, const Array& b, const Array& cg, const Array& up, bool inside) {
        return nesm_edge(finite3(a, "a"), finite3(b, "b"), finite3(cg, "cg"), finite3(up, "up"),
                         inside);
      },
      "a"_a, "b"_a, "cg"_a, "up"_a, "inside"_a,
      "Hirose's normalized energy stability level [m] of the tipping axis through a and b: "
      "h = |R| sqrt(1 - (e.up)^2) - R.up (R the CG offset normal to the axis); -h if not inside.");
  m.def(
      "static_stability_margin",
      [](const Polygon& polygon, const Array& cg, const ProjectionFrame& frame) {
        return static_stability_margin(polygon, vec3(cg, "cg"), frame);
      },
      "polygon"_a, "cg"_a, "frame"_a, "SSM: signed distance of the projected CG to the polygon [m].");
  m.def(
      "energy_stability_margin",
      [](const Polygon& polygon, const Array& contacts, const Array& cg,
         const ProjectionFrame& frame) {
        return energy_stability_margin(polygon, points(contacts, "contacts"), vec3(cg, "cg"), frame);
      },
      "polygon"_a, "contacts"_a, "cg"_a, "frame"_a,
      "NESM [m]: the least normalized energy to tip over an edge of the polygon.");

  py::class_<StabilityMargins>(m, "StabilityMargins",
                               "SSM and NESM w.r.t. the support polygon and the CPS [m].")
      .def_readonly("support_vertices", &StabilityMargins::support_vertices)
      .def_readonly("cps_vertices", &StabilityMargins::cps_vertices)
      .def_readonly("ssm", &StabilityMargins::ssm)
      .def_readonly("nesm", &StabilityMargins::nesm)
      .def_readonly("ssm_cps", &StabilityMargins::ssm_cps)
      .def_readonly("nesm_cps", &StabilityMargins::nesm_cps);
  m.def(
      "stability_margins",
      [](const Array& contacts, const Array& cg, const Array& gravity) {
        return stability_margins(points(contacts, "contacts"), vec3(cg, "cg"),
                                 vec3(gravity, "gravity"));
      },
      "contacts"_a, "cg"_a, "gravity"_a,
      "SSM and NESM of the support polygon and of the CPS for contacts (3, N) (§3.3).");
}

void bind_forces(py::module_& m) {
  py::class_<DistributionInfo>(m, "DistributionInfo", "Rank of A and the equilibrium residual.")
      .def_readonly("rank", &DistributionInfo::rank, "rank of the 6 x 3N equilibrium matrix")
      .def_readonly("residual", &DistributionInfo::residual,
                    "normalised |A f - w| (~1e-16 when equilibrium is reachable)");
  m.def(
      "zero_interaction_forces",
      [](const Array& contacts, const Array& cg, double mass, const Array& gravity) {
        DistributionInfo info;
        Eigen::Matrix3Xd f = zero_interaction_forces(points(contacts, "contacts"), vec3(cg, "cg"),
                                                     mass, vec3(gravity, "gravity"), &info);
        return py::make_tuple(f, info);
      },
      "contacts"_a, "cg"_a, "mass"_a, "gravity"_a,
      "Zero-interaction contact forces (seed 003 §5.1.1), f = A^+ w: returns (forces (3, N) "
      "[N], DistributionInfo).");
}

void bind_sag(py::module_& m) {
  py::class_<SagProblem>(m, "SagProblem",
                         "One stance of the compliance (sag) model (seed 003 §5.1.1, eqs 1–12). "
                         "Point sets are (3, N) arrays.")
      .def(py::init<>())
      .ERNEST_POINTS(SagProblem, feet, "unsagged foot positions r_0,i (3, N) [m], eq 1")
      .ERNEST_POINTS(SagProblem, stiffness, "k_xx, k_yy, k_zz per foot (3, N) [N/m], eq 3")
      .ERNEST_VECN(SagProblem, lift, "Δh_i (N,) [m], eq 9; +inf = foot in the air; empty = 0")
      .ERNEST_VEC3(SagProblem, cg, "unsagged CG r_0,CG [m]")
      .def_readwrite("mass", &SagProblem::mass, "[kg]")
      .ERNEST_VEC3(SagProblem, gravity, "[m/s^2]")
      .ERNEST_MAT3(SagProblem, spring_frame, "columns: x, y, z (normal) spring directions")
      .ERNEST_VEC3(SagProblem, chassis_position, "unsagged chassis origin [m]")
      .ERNEST_MAT3(SagProblem, chassis_rotation, "unsagged chassis orientation")
      .ERNEST_POINTS(SagProblem, body_points, "rigid-body points to report sagged (3, M) [m]")
      .def("validate", &SagProblem::validate, "Raise ValueError naming the first invalid field.");

  py::class_<SagOptions>(m, "SagOptions", "Levenberg–Marquardt and contact-set tolerances.")
      .def(py::init<>())
      .def_readwrite("max_evaluations", &SagOptions::max_evaluations)
      .def_readwrite("tolerance", &SagOptions::tolerance, "LM ftol and xtol")
      .def_readwrite("equilibrium_tolerance", &SagOptions::equilibrium_tolerance)
      .def_readwrite("contact_tolerance", &SagOptions::contact_tolerance,
                     "penetration accepted for an unloaded foot [m]")
      .def("validate", &SagOptions::validate, "Raise ValueError on an invalid field.");

  py::enum_<SagStatus>(m, "SagStatus", "Outcome of a sag solve.")
      .value("Converged", SagStatus::Converged)
      .value("Unstable", SagStatus::Unstable)
      .value("NotConverged", SagStatus::NotConverged);

  py::class_<SagResult>(m, "SagResult", "Forces, deflections and the sagged pose.")
      .def_readonly("status", &SagResult::status)
      .def_readonly("forces", &SagResult::forces, "(3, N) ground reactions [N]")
      .def_readonly("deflections", &SagResult::deflections, "(3, N) foot displacements [m]")
      .def_readonly("compression", &SagResult::compression, "(N,) > 0 loaded [m]")
      .def_readonly("cg", &SagResult::cg, "sagged CG [m]")
      .def_readonly("rotation", &SagResult::rotation, "rigid motion unsagged -> sagged")
      .def_readonly("translation", &SagResult::translation)
      .def_readonly("chassis_position", &SagResult::chassis_position)
      .def_readonly("chassis_rotation", &SagResult::chassis_rotation)
      .def_readonly("body_points", &SagResult::body_points, "(3, M) sagged body points [m]")
      .def_readonly("loaded", &SagResult::loaded)
      .def_readonly("equilibrium_residual", &SagResult::equilibrium_residual)
      .def_readonly("rigidity_residual", &SagResult::rigidity_residual)
      .def_readonly("evaluations", &SagResult::evaluations)
      .def("__repr__", [](const SagResult& r) {
        return std::string("SagResult(status=") + to_string(r.status) +
               ", loaded=" + std::to_string(r.loaded) + ")";
      });

  m.def("solve_sag", &solve_sag, "problem"_a, "options"_a = SagOptions{},
        py::call_guard<py::gil_scoped_release, interruptible>(),
        "Solve one stance of the sag model (eqs 4–8 by Levenberg–Marquardt, eqs 9–12 contact).");
}

void bind_calibration(py::module_& m) {
  py::class_<CalibrationStance>(m, "CalibrationStance",
                                "A measured stance; problem.stiffness is relative (x k).")
      .def(py::init<>())
      .def(py::init([](const SagProblem& problem, const Array& measured_heights) {
             return CalibrationStance{problem, vecn(measured_heights, "measured_heights")};
           }),
           "problem"_a, "measured_heights"_a)
      .def_readwrite("problem", &CalibrationStance::problem)
      .ERNEST_VECN(CalibrationStance, measured_heights, "heights of problem.body_points [m]");
  py::class_<CalibrationOptions>(m, "CalibrationOptions", "Search range and method.")
      .def(py::init<>())
      .def_readwrite("k_min", &CalibrationOptions::k_min, "[N/m]")
      .def_readwrite("k_max", &CalibrationOptions::k_max, "[N/m]")
      .def_readwrite("grid_points", &CalibrationOptions::grid_points, "exhaustive search size")
      .def_readwrite("refine", &CalibrationOptions::refine, "Brent refinement")
      .def_readwrite("brent_bits", &CalibrationOptions::brent_bits)
      .def_readwrite("sag", &CalibrationOptions::sag)
      .def("validate", &CalibrationOptions::validate, "Raise ValueError on an invalid field.");
  py::class_<CalibrationResult>(m, "CalibrationResult", "Best spring constant and its errors.")
      .def_readonly("k_grid", &CalibrationResult::k_grid)
      .def_readonly("error_grid", &CalibrationResult::error_grid)
      .def_readonly("k", &CalibrationResult::k)
      .def_readonly("mean_error", &CalibrationResult::mean_error)
      .def_readonly("max_error", &CalibrationResult::max_error)
      .def_readonly("grid_k", &CalibrationResult::grid_k)
      .def_readonly("grid_error", &CalibrationResult::grid_error)
      .def_readonly("sag_solves", &CalibrationResult::sag_solves);
  py::class_<PerFootCalibrationResult>(m, "PerFootCalibrationResult",
                                       "One spring constant per foot and the height errors.")
      .def_readonly("k", &PerFootCalibrationResult::k, "(N,) [N/m]")
      .def_readonly("mean_error", &PerFootCalibrationResult::mean_error)
      .def_readonly("max_error", &PerFootCalibrationResult::max_error)
      .def_readonly("sag_solves", &PerFootCalibrationResult::sag_solves)
      .def_readonly("lm_status", &PerFootCalibrationResult::lm_status,
                    "Eigen LevenbergMarquardt status (1–4: converged)");
  m.def("calibrate_per_foot_constants", &calibrate_per_foot_constants, "stances"_a,
        "k_initial"_a, "options"_a = SagOptions{}, py::call_guard<py::gil_scoped_release, interruptible>(),
        "One constant per foot (§5.1.4, unequal tyres) by Levenberg–Marquardt on the height "
        "errors over log k, from k_initial.");
  m.def(
      "mean_height_error",
      [](const std::vector<CalibrationStance>& stances, double k, const SagOptions& options) {
        return mean_height_error(stances, k, options);
      },
      "stances"_a, "k"_a, "options"_a = SagOptions{}, py::call_guard<py::gil_scoped_release, interruptible>(),
      "Mean absolute height error [m] of the stances with spring constant k.");
  m.def("calibrate_spring_constant", &calibrate_spring_constant, "stances"_a,
        "options"_a = CalibrationOptions{}, py::call_guard<py::gil_scoped_release, interruptible>(),
        "Spring constant minimising the mean height error (§5.1.3): exhaustive search, then "
        "Brent.");
}

}  // namespace

void bind_statics(py::module_& m) {
  bind_stability(m);
  bind_forces(m);
  bind_sag(m);
  bind_calibration(m);
  bind_statics_rover(m);
}

}  // namespace ernest::bindings
