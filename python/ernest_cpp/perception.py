"""Simulated stereo cameras, OpenCV stereo matching and the robot-centric elevation map of seed 004
§2.4 (Fig. 11). The implementation is C++ (``ernest_cpp._core.perception``), shared with the
environments and the onboard runtime; ``ernest perception`` writes debug views.
"""

from ._core.perception import (  # noqa: F401  (re-exports)
    ElevationMap,
    ElevationMapOptions,
    FuseStats,
    Raycaster,
    RenderOptions,
    StereoAlgorithm,
    StereoCameraParameters,
    StereoFrame,
    StereoMapper,
    StereoMapperOptions,
    StereoMatcher,
    StereoMatcherOptions,
    disparity_to_points,
    opencv_threads,
    set_opencv_threads,
)
