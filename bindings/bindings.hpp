// Declarations of the per-subsystem binding functions called from module.cpp.
#pragma once

#include <pybind11/pybind11.h>

namespace ernest::bindings {
void bind_soil(pybind11::module_& m);
void bind_dynamics(pybind11::module_& m);
void bind_opt(pybind11::module_& m);
void bind_sensing(pybind11::module_& m);
void bind_envs(pybind11::module_& m);
void bind_perception(pybind11::module_& m);
}  // namespace ernest::bindings
