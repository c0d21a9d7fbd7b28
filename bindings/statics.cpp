// Python bindings of cpp/statics: ernest_cpp._core.statics. Each part binds itself
// (bind_statics_rover: ERNEST's mass model and lift-off torque, bindings/statics_rover.cpp).
#include "bindings.hpp"

namespace ernest::bindings {

void bind_statics(pybind11::module_& m) { bind_statics_rover(m); }

}  // namespace ernest::bindings
