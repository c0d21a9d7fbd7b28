// ernest_cpp._core: one submodule per C++ subsystem, each bound in bindings/<subsystem>.cpp.
#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "interrupt.hpp"

PYBIND11_MODULE(_core, m) {
  m.doc() = "C++ core of ernest-cpp (soil, dynamics, optimisation, statics). Use the ernest_cpp package.";
  ernest::bindings::register_interrupt_translator();  // Ctrl-C in long calls (interrupt.hpp)
  auto soil = m.def_submodule("soil", "Bekker–Wong soft soil and rigid contact (seed 004 §3.3–3.4)");
  ernest::bindings::bind_soil(soil);
  auto dynamics = m.def_submodule(
      "dynamics", "ERNEST multibody dynamics on ODE, wheel synchroniser (seed 004 §2–3)");
  ernest::bindings::bind_dynamics(dynamics);
  auto envs = m.def_submodule(
      "envs", "Scenarios (seed 004 §4.5), the episode core and the batched environment");
  ernest::bindings::bind_envs(envs);
  auto opt = m.def_submodule("opt", "Asterix gait transitions with NLopt SLSQP (seed 000)");
  ernest::bindings::bind_opt(opt);
  auto sensing = m.def_submodule(
      "sensing", "Force–torque processing, elevation sampling, observation and reward (seed 004 §4.2–4.3)");
  ernest::bindings::bind_sensing(sensing);
  auto statics = m.def_submodule(
      "statics", "Statics on any set of contacts: stability margins, force distribution, sag model "
                 "and its calibration (seed 003 §3.3, §5.1); ERNEST's mass model and lift-off "
                 "torque (seed 004 §3.2, Fig. 25)");
  ernest::bindings::bind_statics(statics);
  auto walker = m.def_submodule(
      "walker", "ATHLETE-class wheel-on-leg walker: kinematics, IK, joint torques (seed 003)");
  ernest::bindings::bind_walker(walker);
  auto walker_sim = m.def_submodule(
      "walker_sim", "The walker in ODE: swing execution, clearance, sag compensation (seed 003 §4.1)");
  ernest::bindings::bind_walker_sim(walker_sim);
  auto perception = m.def_submodule(
      "perception", "Simulated stereo cameras, OpenCV stereo and the elevation map (seed 004 §2.4)");
  ernest::bindings::bind_perception(perception);
  auto footfall = m.def_submodule(
      "footfall", "FootFall single-leg planning: stability maps, OMPL SBL, smoothing, sag (seed 003)");
  ernest::bindings::bind_footfall(footfall);
  ernest::bindings::add_reprs(m);
}
