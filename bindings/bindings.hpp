// Declarations of the per-subsystem binding functions called from module.cpp.
#pragma once

#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <pybind11/pybind11.h>

#include "pose.hpp"  // to_isometry, shared by the binding files

namespace ernest::bindings {
void bind_soil(pybind11::module_& m);
void bind_dynamics(pybind11::module_& m);
void bind_opt(pybind11::module_& m);
void bind_sensing(pybind11::module_& m);
void bind_envs(pybind11::module_& m);
void bind_statics(pybind11::module_& m);
void bind_statics_rover(pybind11::module_& m);  // part of bind_statics (bindings/statics_rover.cpp)
void bind_walker(pybind11::module_& m);
void bind_walker_gait(pybind11::module_& m);  // part of bind_walker (bindings/walker_gait.cpp)
void bind_walker_sim(pybind11::module_& m);
void bind_perception(pybind11::module_& m);
void bind_perception_selfimage(pybind11::module_& m);  // part of bind_perception (bindings/perception_selfimage.cpp)
void bind_footfall(pybind11::module_& m);
void bind_footfall_terrain(pybind11::module_& m);  // part of bind_footfall (bindings/footfall_terrain.cpp)
// A readable __repr__ for every bound class of `core` that has none (bindings/repr.cpp); call last.
void add_reprs(pybind11::module_& core);
// A number as every __repr__ prints it: the shortest text that reads back to the same double
// (Python's float repr), without a trailing ".0": 0.015, 2, 1e-07, nan (bindings/repr.cpp).
std::string format_number(double x);
}  // namespace ernest::bindings
