// Python bindings of cpp/perception. Argument names equal the C++ names. Poses cross the boundary
// as 4 x 4 homogeneous matrices (camera -> world); images as numpy arrays (uint8 grey, float32
// depth and disparity, row = image row).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "ernest/common/validation.hpp"
#include "exclusive.hpp"
#include "pose.hpp"
#include "ernest/perception/stereo_mapper.hpp"
#include "interrupt.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::perception;

namespace {
py::object optional_height(bool ok, double z) { return ok ? py::object(py::float_(z)) : py::none(); }
}  // namespace

void bind_perception(py::module_& m) {
  using Points = ElevationMap::Points;
  py::class_<StereoCameraParameters>(m, "StereoCameraParameters",
                                     "Rectified stereo pair in ERNEST's masthead (§2.1.2): "
                                     "intrinsics, baseline and mounting on the chassis.")
      .def(py::init<>())
      .def_readwrite("width", &StereoCameraParameters::width, "[px]")
      .def_readwrite("height", &StereoCameraParameters::height, "[px]")
      .def_readwrite("horizontal_fov", &StereoCameraParameters::horizontal_fov, "[rad]")
      .def_readwrite("baseline", &StereoCameraParameters::baseline, "[m]")
      .def_readwrite("mount_position", &StereoCameraParameters::mount_position,
                     "midpoint of the pair in the chassis frame [m]")
      .def_readwrite("mount_pitch", &StereoCameraParameters::mount_pitch, "downward tilt [rad]")
      .def("validate", &StereoCameraParameters::validate, "Raise ValueError on an invalid field.")
      .def("focal", &StereoCameraParameters::focal, "Focal length [px].")
      .def("cx", &StereoCameraParameters::cx, "Principal point u [px].")
      .def("cy", &StereoCameraParameters::cy, "Principal point v [px].")
      .def("chassis_from_camera", &StereoCameraParameters::chassis_from_camera,
           "Rotation camera -> chassis (camera x right, y down, z forward).")
      .def(
          "camera_pose",
          [](const StereoCameraParameters& c, const Eigen::Vector3d& chassis_position,
             const Eigen::Matrix3d& chassis_rotation, int which) {
            return Eigen::Matrix4d(c.camera_pose(chassis_position, chassis_rotation, which).matrix());
          },
          "chassis_position"_a, "chassis_rotation"_a, "which"_a = 0,
          "4 x 4 pose (camera -> world) of the left (0) or right (1) camera.");

  py::class_<RenderOptions>(m, "RenderOptions", "Procedural texture, light and noise of the ray caster.")
      .def(py::init<>())
      .def_readwrite("texture_wavelength", &RenderOptions::texture_wavelength, "[m]")
      .def_readwrite("texture_octaves", &RenderOptions::texture_octaves)
      .def_readwrite("texture_gain", &RenderOptions::texture_gain)
      .def_readwrite("albedo", &RenderOptions::albedo)
      .def_readwrite("contrast", &RenderOptions::contrast)
      .def_readwrite("ambient", &RenderOptions::ambient)
      .def_readwrite("sun_elevation", &RenderOptions::sun_elevation, "[rad]")
      .def_readwrite("sun_azimuth", &RenderOptions::sun_azimuth, "[rad]")
      .def_readwrite("noise_sigma", &RenderOptions::noise_sigma, "[grey levels]")
      .def_readwrite("sky", &RenderOptions::sky, "[grey level]")
      .def_readwrite("max_range", &RenderOptions::max_range, "[m]")
      .def_readwrite("seed", &RenderOptions::seed)
      .def("validate", &RenderOptions::validate, "Raise ValueError on an invalid field.");

  py::class_<Raycaster>(m, "Raycaster",
                        "Deterministic CPU ray caster over a HeightMap and BoxObstacles.")
      .def(py::init<const dynamics::HeightMap&, const std::vector<dynamics::BoxObstacle>&,
                    const RenderOptions&>(),
           "terrain"_a, "boxes"_a, "options"_a = RenderOptions{})
      .def(
          "render",
          [](const Raycaster& r, const Eigen::Matrix4d& pose, const StereoCameraParameters& camera,
             std::uint64_t frame) {
            const Eigen::Isometry3d p = to_isometry(pose, "pose");
            GrayImage image;
            FloatImage depth;
            {
              py::gil_scoped_release release;
              interruptible scope;  // Ctrl-C between image rows
              r.render(p, camera, frame, image, depth);
            }
            return py::make_tuple(image, depth);
          },
          "pose"_a, "camera"_a, "frame"_a = 0,
          "(image uint8 [h, w], depth float32 [h, w] along the optical axis, NaN = sky).")
      .def(
          "intersect",
          [](const Raycaster& r, const Eigen::Vector3d& o, const Eigen::Vector3d& d) -> py::object {
            double t;
            Eigen::Vector3d n;
            if (!r.intersect(o, d.normalized(), t, n)) return py::none();
            return py::make_tuple(t, n);
          },
          "o"_a, "d"_a, "First hit (t, normal) of the ray o + t d (d normalised), or None.")
      .def("surface_height", &Raycaster::surface_height, "x"_a, "y"_a,
           "Top surface height (terrain or box) at (x, y) [m]: the ground truth of the map.")
      .def(
          "surface_heights",
          [](const Raycaster& r, const Eigen::Ref<const Eigen::MatrixXd>& x,
             const Eigen::Ref<const Eigen::MatrixXd>& y) {
            if (x.rows() != y.rows() || x.cols() != y.cols())
              throw std::invalid_argument("surface_heights: x and y have different shapes");
            Eigen::MatrixXd z(x.rows(), x.cols());
            py::gil_scoped_release release;
            interruptible scope;
            for (Eigen::Index i = 0; i < x.rows(); ++i) {
              ernest::poll_interrupt();  // Ctrl-C between rows
              for (Eigen::Index j = 0; j < x.cols(); ++j) z(i, j) = r.surface_height(x(i, j), y(i, j));
            }
            return z;
          },
          "x"_a, "y"_a, "surface_height over arrays of equal shape.")
      .def_property_readonly("lipschitz", &Raycaster::lipschitz, "bound on |grad h|");

  py::enum_<StereoAlgorithm>(m, "StereoAlgorithm", "OpenCV matcher.")
      .value("BlockMatching", StereoAlgorithm::BlockMatching)
      .value("SemiGlobal", StereoAlgorithm::SemiGlobal);

  py::class_<StereoMatcherOptions>(m, "StereoMatcherOptions", "OpenCV StereoBM / StereoSGBM settings.")
      .def(py::init<>())
      .def_readwrite("algorithm", &StereoMatcherOptions::algorithm)
      .def_readwrite("num_disparities", &StereoMatcherOptions::num_disparities, "[px], x16")
      .def_readwrite("block_size", &StereoMatcherOptions::block_size, "odd [px]")
      .def_readwrite("uniqueness_ratio", &StereoMatcherOptions::uniqueness_ratio, "[%]")
      .def_readwrite("texture_threshold", &StereoMatcherOptions::texture_threshold)
      .def_readwrite("speckle_window", &StereoMatcherOptions::speckle_window, "[px]")
      .def_readwrite("speckle_range", &StereoMatcherOptions::speckle_range, "[px]")
      .def_readwrite("pre_filter_cap", &StereoMatcherOptions::pre_filter_cap)
      .def_property(
          "max_lr_difference", [](const StereoMatcherOptions& o) { return o.max_lr_difference; },
          [](StereoMatcherOptions& o, std::optional<int> d) {
            if (d) ernest::require_in_range("StereoMatcherOptions", "max_lr_difference", *d, 0, 1024);
            o.max_lr_difference = d;
          },
          "left-right check tolerance [px], [0, 1024]; None: no check")
      .def("validate", &StereoMatcherOptions::validate, "Raise ValueError on an invalid field.");

  py::class_<StereoMatcher>(m, "StereoMatcher", "OpenCV stereo matcher (StereoBM by default).")
      .def(py::init<const StereoMatcherOptions&>(), "options"_a = StereoMatcherOptions{})
      .def("compute", guarded("StereoMatcher.compute", &StereoMatcher::compute), "left"_a, "right"_a,
           py::call_guard<py::gil_scoped_release, interruptible>(),
           "Disparity [px] (float32, NaN = no match) of two uint8 images of equal size. Ctrl-C "
           "stops it between its OpenCV passes (two with the left-right check) and output rows.")
      .def_property_readonly("options", &StereoMatcher::options);

  m.def("set_opencv_threads", &set_opencv_threads, "threads"_a,
        "Threads the C++ OpenCV may use (cv::setNumThreads, process-wide).");
  m.def("opencv_threads", &opencv_threads, "Threads the C++ OpenCV uses (cv::getNumThreads).");
  m.def(
      "disparity_to_points",
      [](const FloatImage& disparity, const StereoCameraParameters& camera, double min_disparity,
         double max_depth) {
        PointCloud c = disparity_to_points(disparity, camera, min_disparity, max_depth);
        return py::make_tuple(c.points, c.pixels);
      },
      "disparity"_a, "camera"_a, "min_disparity"_a = 0.5, "max_depth"_a = 20.0,
      "(points [n, 3] in the left camera frame [m], pixels [n, 2] (u, v)) of the valid disparities.");

  py::class_<ElevationMapOptions>(m, "ElevationMapOptions", "Robot-centric elevation map (§2.4, [17]).")
      .def(py::init<>())
      .def_readwrite("length", &ElevationMapOptions::length, "[m]")
      .def_readwrite("resolution", &ElevationMapOptions::resolution, "[m]")
      .def_readwrite("disparity_sigma", &ElevationMapOptions::disparity_sigma, "[px]")
      .def_readwrite("pose_variance", &ElevationMapOptions::pose_variance, "[m^2]")
      .def_readwrite("mahalanobis_threshold", &ElevationMapOptions::mahalanobis_threshold)
      .def_readwrite("multi_height_noise", &ElevationMapOptions::multi_height_noise, "[m^2]")
      .def_readwrite("min_variance", &ElevationMapOptions::min_variance, "[m^2]")
      .def("validate", &ElevationMapOptions::validate, "Raise ValueError on an invalid field.");

  py::class_<FuseStats>(m, "FuseStats", "Counts of one fusion (skipped points by reason).")
      .def_readonly("fused_points", &FuseStats::fused_points)
      .def_readonly("non_finite", &FuseStats::non_finite)
      .def_readonly("behind_camera", &FuseStats::behind_camera)
      .def_readonly("outside_map", &FuseStats::outside_map)
      .def_readonly("new_cells", &FuseStats::new_cells)
      .def_readonly("updated_cells", &FuseStats::updated_cells)
      .def_readonly("gated_cells", &FuseStats::gated_cells);

  py::class_<ElevationMap, sensing::HeightSource>(
      m, "ElevationMap", "Robot-centric 2.5-D grid of heights and variances (NaN = hole).")
      .def(py::init<const ElevationMapOptions&>(), "options"_a = ElevationMapOptions{})
      .def("move_to", guarded("ElevationMap.move_to", &ElevationMap::move_to), "x"_a, "y"_a, "Centre the window on (x, y).")
      .def(
          "fuse_cloud",
          [](ElevationMap& map, const Eigen::Ref<const Points>& points, const Eigen::Matrix4d& pose,
             const StereoCameraParameters& camera) {
            const Eigen::Isometry3d p = to_isometry(pose, "camera_pose");
            const Busy busy("ElevationMap.fuse_cloud", {&map});
            py::gil_scoped_release release;
            interruptible scope;  // Ctrl-C before any cell changes
            return map.fuse_cloud(points, p, camera);
          },
          "points"_a, "camera_pose"_a, "camera"_a,
          "Fuse camera-frame points [n, 3] seen from camera_pose (4 x 4) with the stereo noise model.")
      .def("fuse_points", guarded("ElevationMap.fuse_points", &ElevationMap::fuse_points), "points"_a, "variances"_a,
           py::call_guard<py::gil_scoped_release>(),
           "Fuse world points [n, 3] with height variances [n] (one measurement per cell per call).")
      .def("measurement_variance", &ElevationMap::measurement_variance, "p_cam"_a,
           "camera_rotation"_a, "camera"_a,
           "Height variance of a camera-frame point [m^2] (p_cam.z > 0: in front of the camera).")
      .def(
          "height",
          [](const ElevationMap& map, double x, double y) {
            const Busy busy("ElevationMap.height", {&map});
            double z = 0.0;
            const bool ok = map.height(x, y, z);
            return optional_height(ok, z);
          },
          "x"_a, "y"_a, "Height of the cell holding (x, y), or None in a hole.")
      .def(
          "cell",
          [](const ElevationMap& map, double x, double y) {
            const Busy busy("ElevationMap.cell", {&map});
            double z, v;
            map.cell(x, y, z, v);
            return py::make_tuple(z, v);
          },
          "x"_a, "y"_a, "(height, variance) of the cell holding (x, y); (nan, inf) for a hole.")
      .def("clear", guarded("ElevationMap.clear", &ElevationMap::clear), "Make every cell a hole.")
      .def_property_readonly("heights", guarded("ElevationMap.heights", &ElevationMap::heights),
                             "[n, n], (i, j) at origin + (i, j) * resolution; NaN = hole")
      .def_property_readonly("variances", guarded("ElevationMap.variances", &ElevationMap::variances), "[n, n] [m^2]; inf = hole")
      .def_property_readonly("origin_x", guarded("ElevationMap.origin_x", &ElevationMap::origin_x), "[m]")
      .def_property_readonly("origin_y", guarded("ElevationMap.origin_y", &ElevationMap::origin_y), "[m]")
      .def_property_readonly("cells", &ElevationMap::cells, "cells per side")
      .def_property_readonly("resolution", &ElevationMap::resolution, "[m]")
      .def_property_readonly("skipped_empty", guarded("ElevationMap.skipped_empty", &ElevationMap::skipped_empty), "empty clouds skipped")
      .def("consistent", guarded("ElevationMap.consistent", &ElevationMap::consistent),
           "True if every cell is a hole (NaN, inf) or known (finite, finite > 0).");

  py::class_<StereoMapperOptions>(m, "StereoMapperOptions", "Camera, renderer, matcher, map and rate.")
      .def(py::init<>())
      .def_readwrite("camera", &StereoMapperOptions::camera)
      .def_readwrite("render", &StereoMapperOptions::render)
      .def_readwrite("matcher", &StereoMapperOptions::matcher)
      .def_readwrite("map", &StereoMapperOptions::map)
      .def_readwrite("fusion_rate", &StereoMapperOptions::fusion_rate, "[Hz] (§2.4: 0.5)")
      .def_readwrite("max_depth", &StereoMapperOptions::max_depth, "[m]")
      .def("validate", &StereoMapperOptions::validate, "Raise ValueError on an invalid field.");

  py::class_<StereoFrame>(m, "StereoFrame", "The last captured stereo frame (debug views).")
      .def_readonly("left", &StereoFrame::left)
      .def_readonly("right", &StereoFrame::right)
      .def_readonly("depth", &StereoFrame::depth)
      .def_readonly("disparity", &StereoFrame::disparity)
      .def_property_readonly("points", [](const StereoFrame& f) { return f.cloud.points; })
      .def_property_readonly("pixels", [](const StereoFrame& f) { return f.cloud.pixels; })
      .def_property_readonly("left_pose",
                             [](const StereoFrame& f) { return Eigen::Matrix4d(f.left_pose.matrix()); })
      .def_readonly("stats", &StereoFrame::stats);

  py::class_<StereoMapper, std::shared_ptr<StereoMapper>>(m, "StereoMapper",
                           "Render, match (StereoBM) and fuse at the fusion rate (§2.4 pipeline).")
      .def(py::init<const dynamics::HeightMap&, const std::vector<dynamics::BoxObstacle>&,
                    const StereoMapperOptions&>(),
           "terrain"_a, "boxes"_a, "options"_a = StereoMapperOptions{})
      .def("update",
           [](StereoMapper& s, double time, const Eigen::Vector3d& p, const Eigen::Matrix3d& r) {
             const Busy busy("StereoMapper.update", {&s, &s.map()});
             py::gil_scoped_release release;
             interruptible scope;
             return s.update(time, p, r);
           },
           "time"_a, "chassis_position"_a, "chassis_rotation"_a,
           "Re-centre the map; capture and fuse if a fusion is due. Returns whether it fused.")
      .def(
          "capture",
          [](StereoMapper& s, const Eigen::Vector3d& p, const Eigen::Matrix3d& r) {
            const Busy busy("StereoMapper.capture", {&s, &s.map()});
            py::gil_scoped_release release;
            interruptible scope;
            s.capture(p, r);
          },
          "chassis_position"_a, "chassis_rotation"_a, "Capture and fuse one frame now.")
      .def("reset",
           [](StereoMapper& s) {
             const Busy busy("StereoMapper.reset", {&s, &s.map()});
             s.reset();
           },
           "Empty the map and the schedule.")
      .def_property_readonly("map", &StereoMapper::map, py::return_value_policy::reference_internal)
      .def_property_readonly("last_frame", guarded("StereoMapper.last_frame", &StereoMapper::last_frame),
                             py::return_value_policy::reference_internal)
      .def_property_readonly("raycaster", &StereoMapper::raycaster,
                             py::return_value_policy::reference_internal)
      .def_property_readonly("frames", guarded("StereoMapper.frames", &StereoMapper::frames), "frames fused so far");

  bind_perception_selfimage(m);  // the walker's self-imaging (seed 003 §4.3, §5.2)
}

}  // namespace ernest::bindings
