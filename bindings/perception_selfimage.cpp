// Python bindings of the self-imaging part of cpp/perception (self_render, self_scene,
// self_image; seed 003 §4.3, §5.2), in the same submodule as the rest of perception (called from
// bind_perception). Argument names equal the C++ names; poses are 4 x 4 matrices.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "exclusive.hpp"
#include "interrupt.hpp"
#include "pose.hpp"
#include "ernest/perception/self_image.hpp"
#include "ernest/perception/self_scene.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ernest::bindings {

using namespace ernest::perception;


void bind_perception_selfimage(py::module_& m) {
  py::enum_<RobotSolid::Kind>(m, "RobotSolidKind", "Shape of a robot solid.")
      .value("Capsule", RobotSolid::Kind::Capsule)
      .value("Cylinder", RobotSolid::Kind::Cylinder);
  py::class_<RobotSolid>(m, "RobotSolid",
                         "A capsule or capped cylinder of the robot (world frame), label >= 1.")
      .def(py::init<>())
      .def_readwrite("kind", &RobotSolid::kind)
      .def_readwrite("p0", &RobotSolid::p0, "[m]")
      .def_readwrite("p1", &RobotSolid::p1, "[m]")
      .def_readwrite("radius", &RobotSolid::radius, "[m]")
      .def_readwrite("label", &RobotSolid::label, "written to the label image (leg + 1)");
  m.def("intersect_solid", &intersect_solid, "s"_a, "o"_a, "d"_a,
        "Entry distance t > 0 of the ray o + t d (d unit) into the solid, negative if it misses.");
  m.def(
      "walker_solids",
      [](const walker::WalkerModel& model, const Eigen::Matrix4d& body, const Eigen::MatrixXd& q) {
        return walker_solids(model, to_isometry(body, "body"), q);
      },
      "model"_a, "body"_a, "q"_a,
      "Every link capsule and wheel cylinder of the walker (label = leg + 1) for a body pose (4 x 4) "
      "and q (joints x legs).");
  m.def("walker_hazcam", &walker_hazcam,
        "The walker's hazard camera pair (ours: under the chassis, facing a leg, 40° down).");
  m.def(
      "hazcam_pose",
      [](const walker::WalkerModel& model, const Eigen::Matrix4d& body, int leg,
         const StereoCameraParameters& camera) {
        return Eigen::Matrix4d(hazcam_pose(model, to_isometry(body, "body"), leg, camera).matrix());
      },
      "model"_a, "body"_a, "leg"_a, "camera"_a, "4 x 4 pose of the left hazcam facing `leg`.");

  py::class_<SelfRenderOptions>(m, "SelfRenderOptions", "Depth noise and robot shade of the self-image render.")
      .def(py::init<>())
      .def_readwrite("disparity_sigma", &SelfRenderOptions::disparity_sigma,
                     "Gaussian disparity noise [px] (0 = exact depth)")
      .def_readwrite("robot_grey", &SelfRenderOptions::robot_grey, "[grey level]")
      .def_readwrite("seed", &SelfRenderOptions::seed)
      .def("validate", &SelfRenderOptions::validate, "Raise ValueError on an invalid field.");
  m.def(
      "render_with_robot",
      [](const Raycaster& scene, const std::vector<RobotSolid>& solids, const Eigen::Matrix4d& pose,
         const StereoCameraParameters& camera, const SelfRenderOptions& options, std::uint64_t frame) {
        const Eigen::Isometry3d p = to_isometry(pose, "pose");
        SelfImageFrame f;
        {
          py::gil_scoped_release release;
          interruptible scope;
          render_with_robot(scene, solids, p, camera, options, frame, f);
        }
        return py::make_tuple(f.image, f.depth, f.labels);
      },
      "scene"_a, "solids"_a, "pose"_a, "camera"_a, "options"_a = SelfRenderOptions{}, "frame"_a = 0,
      "(image uint8, depth float32 [m] (+inf = no return), labels int32 (0 terrain, leg + 1, -1 "
      "nothing)) of the terrain and the solids ray-cast together.");

  py::class_<SelfImageScene>(m, "SelfImageScene", "Walker on undulating ground with a ring of rocks.")
      .def_readonly("terrain", &SelfImageScene::terrain)
      .def_readonly("rocks", &SelfImageScene::rocks)
      .def_property_readonly("body", [](const SelfImageScene& s) { return Eigen::Matrix4d(s.body.matrix()); },
                             "4 x 4 body pose")
      .def_readonly("q", &SelfImageScene::q, "standard configuration (joints x legs)");
  m.def("self_image_scene", &self_image_scene, "model"_a, "seed"_a, "rocks"_a = 12,
        "The seeded self-imaging scene (tests, benchmark and demo).");
  m.def("raised_leg", &raised_leg, "model"_a, "leg"_a, "lift"_a, "reach"_a,
        "Joint angles of `leg` with the wheel lifted by `lift` and moved out by `reach` [m] (IK).");

  py::class_<SelfImageOptions>(m, "SelfImageOptions", "Watershed self-image segmentation (§5.2).")
      .def(py::init<>())
      .def_readwrite("smoothing_sigma", &SelfImageOptions::smoothing_sigma, "[px]")
      .def_readwrite("marker_gradient", &SelfImageOptions::marker_gradient,
                     "marker where |grad D| is below this [px/px]")
      .def_readwrite("min_marker_pixels", &SelfImageOptions::min_marker_pixels)
      .def_readwrite("connect_jump", &SelfImageOptions::connect_jump, "[px of disparity]")
      .def_readwrite("connect_fraction", &SelfImageOptions::connect_fraction)
      .def_readwrite("min_connect_pairs", &SelfImageOptions::min_connect_pairs)
      .def_readwrite("min_area_fraction", &SelfImageOptions::min_area_fraction)
      .def_readwrite("max_area_fraction", &SelfImageOptions::max_area_fraction)
      .def_readwrite("dilate_pixels", &SelfImageOptions::dilate_pixels)
      .def("validate", &SelfImageOptions::validate, "Raise ValueError on an invalid field.");
  py::class_<SelfImageResult>(m, "SelfImageResult", "Removed mask, segments and objects of one depth map.")
      .def_readonly("removed", &SelfImageResult::removed, "uint8, 1 = the leg (not fused)")
      .def_readonly("segments", &SelfImageResult::segments, "int32 watershed segments (1 = no return)")
      .def_readonly("objects", &SelfImageResult::objects, "int32 merged objects (0 = no return)")
      .def_readonly("segment_count", &SelfImageResult::segment_count)
      .def_readonly("object_count", &SelfImageResult::object_count)
      .def_readonly("ground_object", &SelfImageResult::ground_object)
      .def_readonly("leg_object", &SelfImageResult::leg_object, "0 = none found")
      .def_readonly("removed_pixels", &SelfImageResult::removed_pixels)
      .def_readonly("leg_mean_depth", &SelfImageResult::leg_mean_depth, "[m]")
      .def("found", &SelfImageResult::found, "True if a leg segment was removed.");
  py::class_<SelfImageSegmenter>(m, "SelfImageSegmenter", "Watershed removal of the raised leg (§5.2).")
      .def(py::init<const SelfImageOptions&>(), "options"_a = SelfImageOptions{})
      .def("segment",
           guarded("SelfImageSegmenter.segment",
                   py::overload_cast<const FloatImage&, const StereoCameraParameters&>(&SelfImageSegmenter::segment)),
           "depth"_a, "camera"_a, py::call_guard<py::gil_scoped_release, interruptible>(),
           "Segment a depth map [m] (+inf = no return) of the camera's size; ValueError on NaN, "
           "z <= 0 or a wrong size.")
      .def_property_readonly("options", &SelfImageSegmenter::options);
  m.def(
      "mask_iou",
      [](const py::array& a, const py::array& b) {
        // A float mask would be truncated to 0 silently (0.3 -> 0): masks are bool or 0/1 integers.
        const auto as_mask = [](const py::array& x, const char* name) {
          const char kind = x.dtype().kind();
          if (kind != 'b' && kind != 'u' && kind != 'i') {
            throw py::type_error(std::string("mask_iou: ") + name +
                                 " must be a bool or integer 0/1 mask, got dtype " +
                                 py::str(x.dtype()).cast<std::string>());
          }
          if (x.ndim() != 2) {
            throw std::invalid_argument(std::string("mask_iou: ") + name + " must be 2-D");
          }
          const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> v(x);
          MaskImage m(v.shape(0), v.shape(1));
          const std::int64_t* d = v.data();
          for (Eigen::Index i = 0; i < m.size(); ++i) {
            if (d[i] != 0 && d[i] != 1) {
              throw std::invalid_argument(std::string("mask_iou: ") + name +
                                          " must hold only 0 and 1, got " + std::to_string(d[i]));
            }
            m.data()[i] = static_cast<std::uint8_t>(d[i]);
          }
          return m;
        };
        return mask_iou(as_mask(a, "a"), as_mask(b, "b"));
      },
      "a"_a, "b"_a, "Intersection over union of two 0/1 masks (bool or integer).");
  m.def(
      "depth_to_points",
      [](const FloatImage& depth, const StereoCameraParameters& camera, const MaskImage& removed,
         double max_depth) {
        PointCloud c = depth_to_points(depth, camera, removed, max_depth);
        return py::make_tuple(c.points, c.pixels);
      },
      "depth"_a, "camera"_a, "removed"_a, "max_depth"_a = 20.0,
      "(points [n, 3] left camera frame, pixels [n, 2]) of the depth map outside `removed` "
      "(pass an empty array to keep all).");
}

}  // namespace ernest::bindings
