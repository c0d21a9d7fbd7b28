// Python bindings of cpp/walker/gait_planner (seed 003 §5.3.1, FootFall's skeleton gait); part of
// ernest_cpp._core.walker (called from bind_walker).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "interrupt.hpp"
#include "ernest/walker/gait_planner.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::walker;

void bind_walker_gait(py::module_& m) {
  py::class_<GaitPlannerOptions>(m, "GaitPlannerOptions",
                                 "Skeleton-gait settings (seed 003 §5.3.1): reverse wave, step "
                                 "lengths by successive IK, body shifts with all feet down.")
      .def(py::init<>())
      .def_readwrite("heading", &GaitPlannerOptions::heading, "direction of travel [rad]")
      .def_readwrite("cycles", &GaitPlannerOptions::cycles, "gait cycles, [1, 100]")
      .def_readwrite("max_step", &GaitPlannerOptions::max_step, "longest step [m], (0, 5]")
      .def_readwrite("lift_height", &GaitPlannerOptions::lift_height, "compliance waypoints [m]")
      .def_readwrite("min_support_margin", &GaitPlannerOptions::min_support_margin,
                     "SSM required with a leg in the air [m]")
      .def_readwrite("search_increment", &GaitPlannerOptions::search_increment,
                     "successive IK tests every this much [m]")
      .def_readwrite("search_tolerance", &GaitPlannerOptions::search_tolerance,
                     "bisection of the last interval to this [m]")
      .def_readwrite("ik_seeds", &GaitPlannerOptions::ik_seeds, "multi-start IK seeds")
      .def_readwrite("sequence", &GaitPlannerOptions::sequence, "stepping order; [] = reverse wave")
      .def("validate", &GaitPlannerOptions::validate, "legs"_a, "Raise ValueError naming the first invalid field.");

  py::enum_<GaitEvent::Kind>(m, "GaitEventKind")
      .value("Step", GaitEvent::kStep)
      .value("Shift", GaitEvent::kShift);

  py::class_<GaitEvent>(m, "GaitEvent", "A step of one leg (body still) or a body shift (feet still).")
      .def_readonly("kind", &GaitEvent::kind)
      .def_readonly("cycle", &GaitEvent::cycle)
      .def_readonly("leg", &GaitEvent::leg, "stepping leg, -1 for a shift")
      .def_readonly("length", &GaitEvent::length, "[m]")
      .def_readonly("body_before", &GaitEvent::body_before, "world [m]")
      .def_readonly("body_after", &GaitEvent::body_after, "world [m]")
      .def_readonly("feet_before", &GaitEvent::feet_before, "wheel contacts, 3 × legs [m]")
      .def_readonly("feet_after", &GaitEvent::feet_after, "wheel contacts, 3 × legs [m]")
      .def_readonly("q_before", &GaitEvent::q_before, "joints × legs [rad]")
      .def_readonly("q_after", &GaitEvent::q_after, "joints × legs [rad]")
      .def_readonly("q_lift_start", &GaitEvent::q_lift_start, "leg at the waypoint above the start")
      .def_readonly("q_lift_goal", &GaitEvent::q_lift_goal, "leg at the waypoint above the goal")
      .def_readonly("support_margin", &GaitEvent::support_margin, "smallest SSM during the event [m]");

  py::class_<GaitPlan>(m, "GaitPlan", "The skeleton gait: events and the step and shift lengths per cycle.")
      .def_readonly("sequence", &GaitPlan::sequence)
      .def_readonly("events", &GaitPlan::events)
      .def_readonly("step_lengths", &GaitPlan::step_lengths, "cycles × steps (sequence order) [m]")
      .def_readonly("shift_lengths", &GaitPlan::shift_lengths, "cycles × shifts (after each step) [m]")
      .def_readonly("ik_tests", &GaitPlan::ik_tests)
      .def_readonly("seconds", &GaitPlan::seconds);

  m.def("reverse_wave_sequence", &reverse_wave_sequence, "model"_a, "heading"_a,
        "Legs front to rear along `heading`, left first at equal depth (§5.3.1).");
  m.def("plan_gait", &plan_gait, "model"_a, "body_position"_a, "q"_a, "options"_a = GaitPlannerOptions{},
        py::call_guard<py::gil_scoped_release, interruptible>(),
        "Plan options.cycles gait cycles on flat ground from a level body at `body_position` and "
        "configuration q (joints × legs, wheels on z = 0).");
}

}  // namespace ernest::bindings
