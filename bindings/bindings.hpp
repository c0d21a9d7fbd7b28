// Declarations of the per-subsystem binding functions called from module.cpp.
#pragma once

#include <pybind11/pybind11.h>

namespace ernest::bindings {
void bind_soil(pybind11::module_& m);
void bind_dynamics(pybind11::module_& m);
void bind_opt(pybind11::module_& m);
void bind_sensing(pybind11::module_& m);
void bind_envs(pybind11::module_& m);
void bind_statics(pybind11::module_& m);
void bind_statics_rover(pybind11::module_& m);  // part of bind_statics (bindings/statics_rover.cpp)
void bind_walker(pybind11::module_& m);
void bind_perception(pybind11::module_& m);
void bind_perception_selfimage(pybind11::module_& m);  // part of bind_perception (bindings/perception_selfimage.cpp)
}  // namespace ernest::bindings
