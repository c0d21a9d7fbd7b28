"""Simulated stereo cameras, OpenCV stereo matching and the robot-centric elevation map of seed 004
§2.4 (Fig. 11), and the walker's self-imaging (seed 003 §4.3, §5.2: the raised leg rendered into
the hazard camera's depth map and removed by watershed segmentation before fusion; see
``perception_selfimage``). The implementation is C++ (``ernest_cpp._core.perception``), shared with
the environments and the onboard runtime; ``ernest perception`` writes debug views.
"""

from ._core.perception import (  # noqa: F401  (re-exports)
    ElevationMap,
    ElevationMapOptions,
    FuseStats,
    Raycaster,
    RenderOptions,
    RobotSolid,
    RobotSolidKind,
    SelfImageOptions,
    SelfImageResult,
    SelfImageScene,
    SelfImageSegmenter,
    SelfRenderOptions,
    StereoAlgorithm,
    StereoCameraParameters,
    StereoFrame,
    StereoMapper,
    StereoMapperOptions,
    StereoMatcher,
    StereoMatcherOptions,
    depth_to_points,
    disparity_to_points,
    hazcam_pose,
    intersect_solid,
    mask_iou,
    opencv_threads,
    raised_leg,
    render_with_robot,
    self_image_scene,
    set_opencv_threads,
    walker_hazcam,
    walker_solids,
)
