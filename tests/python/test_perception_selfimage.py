"""Python side of the walker's self-imaging (seed 003 §4.3, §5.2): the bindings (solids, render,
watershed segmentation, depth back-projection), bad input as ValueError, and the demo the
``ernest footfall`` command calls (figure written, IoU >= 0.9, the false obstacle removed)."""

import math

import numpy as np
import pytest

from ernest_cpp import perception as P
from ernest_cpp import perception_selfimage as SI
from ernest_cpp import walker as W


@pytest.fixture(scope="module")
def setup():
    model = W.WalkerModel(W.sdm_b_parameters())
    scene = P.self_image_scene(model, 3)
    caster = P.Raycaster(scene.terrain, list(scene.rocks))
    return model, scene, caster, P.walker_hazcam()


def test_solids_and_closed_form():
    s = P.RobotSolid()
    s.kind = P.RobotSolidKind.Cylinder
    s.p0, s.p1, s.radius = [5.0, -0.1, 0.0], [5.0, 0.1, 0.0], 0.5
    # a ray 0.4 above the axis: enters at 5 - sqrt(0.5^2 - 0.4^2)
    assert math.isclose(P.intersect_solid(s, [0, 0, 0.4], [1, 0, 0]), 4.7, abs_tol=1e-12)
    assert P.intersect_solid(s, [0, 0, 0.6], [1, 0, 0]) < 0


def test_segmentation_matches_the_rendered_leg(setup):
    model, scene, caster, camera = setup
    image, depth, labels, pose = SI.render_pose(model, scene, caster, camera, 3, 0.5, 0.1)
    assert image.shape == depth.shape == labels.shape == (camera.height, camera.width)
    assert depth.dtype == np.float32 and labels.dtype == np.int32
    res = P.SelfImageSegmenter().segment(depth, camera)
    assert res.found() and res.leg_object != res.ground_object
    assert P.mask_iou(res.removed, (labels == 4).astype(np.uint8)) >= 0.9
    # the removed pixels are the nearest ones: closer than the ground's median depth
    assert res.leg_mean_depth < np.median(depth[np.isfinite(depth)])
    kept, _ = P.depth_to_points(depth, camera, res.removed, 20.0)
    everything, _ = P.depth_to_points(depth, camera, np.zeros((0, 0), np.uint8), 20.0)
    assert len(everything) - len(kept) == res.removed_pixels


def test_bad_input_is_value_error(setup):
    _, _, _, camera = setup
    seg = P.SelfImageSegmenter()
    with pytest.raises(ValueError, match="empty"):
        seg.segment(np.zeros((0, 0), np.float32), camera)
    with pytest.raises(ValueError, match="camera's is 480 x 640"):
        seg.segment(np.full((48, 64), 3.0, np.float32), camera)
    d = np.full((480, 640), 3.0, np.float32)
    d[10, 20] = np.nan
    with pytest.raises(ValueError, match=r"depth\(10, 20\)"):
        seg.segment(d, camera)
    o = P.SelfImageOptions()
    o.min_marker_pixels = 0
    with pytest.raises(ValueError, match="SelfImageOptions.min_marker_pixels = 0"):
        P.SelfImageSegmenter(o)
    with pytest.raises(ValueError, match="body is not finite"):
        P.walker_solids(W.WalkerModel(W.sdm_b_parameters()), np.full((4, 4), np.nan),
                        np.zeros((6, 6)))


def test_demo_writes_the_figure_and_scores(tmp_path):
    res = SI.demo(str(tmp_path), poses=SI.POSES[:2])
    assert (tmp_path / "selfimage.png").stat().st_size > 10_000
    assert (tmp_path / "selfimage.json").exists()
    assert len(res["poses"]) == 2 and res["min_iou"] >= 0.9
    assert res["false_obstacle_before_m"] > 0.3     # the leg is an obstacle without removal
    assert res["false_obstacle_after_m"] <= SI.TOLERANCE  # and gone with it
    assert res["leg_cells"] > 100
