// Declarations of the per-subsystem binding functions called from module.cpp.
#pragma once

#include <Eigen/Geometry>
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

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
/// A 4 × 4 homogeneous transform from Python, checked (finite, rigid, last row 0 0 0 1);
/// std::invalid_argument naming `field` otherwise (bindings/walker.cpp).
Eigen::Isometry3d to_isometry(const Eigen::Matrix4d& t, const char* field);
void bind_perception(pybind11::module_& m);
void bind_footfall(pybind11::module_& m);
}  // namespace ernest::bindings
