// Python bindings of cpp/footfall/terrain_map (the planner's DEM from the fused stereo map), in the
// footfall submodule (called from bind_footfall). Argument names equal the C++ names.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "exclusive.hpp"
#include "ernest/footfall/terrain_map.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::footfall;

void bind_footfall_terrain(py::module_& m) {
  py::class_<MapTerrainOptions>(m, "MapTerrainOptions",
                                "Elevation map -> planner DEM: raise by k sigma, fill small holes from above, "
                                "unseen = obstacle column (footfall/terrain_map.hpp).")
      .def(py::init<>())
      .def_readwrite("spacing", &MapTerrainOptions::spacing, "planner DEM spacing [m]")
      .def_readwrite("sigma_factor", &MapTerrainOptions::sigma_factor, "k: heights raised by k sigma")
      .def_readwrite("max_sigma", &MapTerrainOptions::max_sigma, "less certain cells count as unseen [m]")
      .def_readwrite("fill_radius", &MapTerrainOptions::fill_radius, "holes this close to a seen cell are filled [m]")
      .def_readwrite("unknown_height", &MapTerrainOptions::unknown_height,
                     "unknown vertices stand this far above the highest seen point [m]")
      .def("validate", &MapTerrainOptions::validate, "Raises ValueError naming a bad field.");
  py::enum_<TerrainCell>(m, "TerrainCell", "Planner vertex: observed, filled (small holes) or unknown (obstacle).")
      .value("Observed", TerrainCell::kObserved)
      .value("Filled", TerrainCell::kFilled)
      .value("Unknown", TerrainCell::kUnknown);
  py::class_<MapTerrain>(m, "MapTerrain", "The planner's DEM from an elevation map, with the state of each vertex.")
      .def_readonly("terrain", &MapTerrain::terrain, "dynamics.HeightMap for the planner")
      .def_readonly("state", &MapTerrain::state, "uint8 TerrainCell per vertex")
      .def_readonly("observed", &MapTerrain::observed)
      .def_readonly("filled", &MapTerrain::filled)
      .def_readonly("unknown", &MapTerrain::unknown)
      .def_readonly("filled_cells", &MapTerrain::filled_cells, "map cells filled from neighbours")
      .def_readonly("top", &MapTerrain::top, "highest seen (raised) height [m]")
      .def("unknown_at", &MapTerrain::unknown_at, "x"_a, "y"_a, "Unknown (or outside) at (x, y).");
  m.def("terrain_from_map",
        guarded("terrain_from_map",
                py::overload_cast<const perception::ElevationMap&, const MapTerrainOptions&>(&terrain_from_map)),
        "map"_a,
        "options"_a = MapTerrainOptions{}, py::call_guard<py::gil_scoped_release>(),
        "The planner's DEM from a fused stereo ElevationMap; ValueError when nothing was seen.");
  m.def("terrain_from_arrays",
        py::overload_cast<const Eigen::Ref<const Eigen::MatrixXd>&, const Eigen::Ref<const Eigen::MatrixXd>&, double,
                          double, double, const MapTerrainOptions&>(&terrain_from_map),
        "heights"_a, "variances"_a, "resolution"_a, "origin_x"_a, "origin_y"_a, "options"_a = MapTerrainOptions{},
        py::call_guard<py::gil_scoped_release>(),
        "As terrain_from_map from snapshot arrays (NaN / inf = unseen), cell (i, j) at origin + (i, j) resolution.");
}

}  // namespace ernest::bindings
