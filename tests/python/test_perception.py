"""Python side of cpp/perception (seed 004 §2.4): bindings, the StereoBM wrapper against cv2 on the
same images, the elevation map as a HeightSource for the §4.2 sampler, the terrain_source="stereo"
environments (check_env, vector env) and the ``ernest perception`` command."""

import math

import cv2
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import ernest_cpp.envs as E
from ernest_cpp import dynamics as D
from ernest_cpp import perception as P
from ernest_cpp import sensing
from ernest_cpp.cli import main as cli_main


def _pair(boxes=()):
    terrain = D.HeightMap.flat(30.0, 20.0, 0.05, 0.0, -5.0, -10.0)
    cam = P.StereoCameraParameters()
    rc = P.Raycaster(terrain, list(boxes))
    pos, rot = np.array([0.0, 0.0, 0.17]), np.eye(3)
    left, depth = rc.render(cam.camera_pose(pos, rot, 0), cam, 0)
    right, _ = rc.render(cam.camera_pose(pos, rot, 1), cam, 1)
    return cam, rc, left, right, depth


def test_camera_defaults_and_validation():
    cam = P.StereoCameraParameters()
    assert (cam.width, cam.height) == (640, 480)
    assert math.isclose(cam.mount_pitch, math.radians(30.0))  # §2.1.2
    assert math.isclose(cam.mount_position[2] + 0.17, 1.30)   # Table 1 masthead height
    pose = cam.camera_pose(np.zeros(3), np.eye(3), 0)
    assert pose.shape == (4, 4) and np.allclose(pose[3], [0, 0, 0, 1])
    cam.baseline = 0.0
    with pytest.raises(ValueError, match="baseline = 0"):
        cam.validate()


def test_render_gives_images_and_exact_depth():
    cam, rc, left, right, depth = _pair()
    assert left.shape == (480, 640) and left.dtype == np.uint8
    assert depth.dtype == np.float32
    # pixel (u, v) looks along R (x, y, 1), x = (u - cx) / f: it meets the ground (1.30 m below the
    # camera) at depth Z = 1.30 / -(R (x, y, 1))_z; near the centre Z ~ 1.3 / sin 30 deg = 2.6 m
    pose = cam.camera_pose(np.array([0.0, 0.0, 0.17]), np.eye(3), 0)
    for u, v in ((320, 240), (100, 400), (600, 200)):
        ray = pose[:3, :3] @ np.array([(u - cam.cx()) / cam.focal(), (v - cam.cy()) / cam.focal(), 1.0])
        assert depth[v, u] == pytest.approx(1.30 / -ray[2], rel=1e-6)
    assert depth[240, 320] == pytest.approx(2.6, rel=0.01)
    assert np.isnan(depth[0]).all()          # top row: sky
    assert left.std() > 20 and not np.array_equal(left, right)


def test_stereo_bm_equals_cv2_on_the_same_pair():
    cam, _, left, right, depth = _pair()
    o = P.StereoMatcherOptions()
    checked = P.StereoMatcher(o).compute(left, right)
    o.max_lr_difference = None  # cv2's StereoBM has no left-right check: compare without ours
    ours = P.StereoMatcher(o).compute(left, right)
    # the check only removes matches
    assert np.all(np.isfinite(ours)[np.isfinite(checked)])
    assert 0.8 * np.isfinite(ours).sum() < np.isfinite(checked).sum() < np.isfinite(ours).sum()
    bm = cv2.StereoBM_create(numDisparities=o.num_disparities, blockSize=o.block_size)
    bm.setUniquenessRatio(o.uniqueness_ratio)
    bm.setTextureThreshold(o.texture_threshold)
    bm.setSpeckleWindowSize(o.speckle_window)
    bm.setSpeckleRange(o.speckle_range)
    bm.setPreFilterCap(o.pre_filter_cap)
    ref = bm.compute(left, right).astype(np.float32) / 16.0
    ref[ref < 0] = np.nan
    both = np.isfinite(ours) & np.isfinite(ref)
    # Debian's OpenCV and the wheel's may differ in version: the same algorithm agrees on
    # nearly every pixel
    assert both.sum() > 0.95 * max(np.isfinite(ours).sum(), np.isfinite(ref).sum())
    assert np.mean(np.abs(ours[both] - ref[both]) < 1e-3) > 0.99
    pts, pix = P.disparity_to_points(ours, cam)
    assert pts.shape[1] == 3 and pix.shape == (pts.shape[0], 2)
    # Z = f B / d at every point
    d = ours[pix[:, 1], pix[:, 0]]
    np.testing.assert_allclose(pts[:, 2], cam.focal() * cam.baseline / d, rtol=1e-6)


def test_bad_images_raise():
    m = P.StereoMatcher()
    a = np.zeros((480, 640), np.uint8)
    with pytest.raises(ValueError, match="640x480 but right is 320x480"):
        m.compute(a, np.zeros((480, 320), np.uint8))
    o = P.StereoMatcherOptions()
    o.block_size = 4
    with pytest.raises(ValueError, match="block_size = 4"):
        P.StereoMatcher(o)


def test_elevation_map_update_holes_and_sampler():
    o = P.ElevationMapOptions()
    assert (o.length, o.resolution) == (10.0, 0.01)  # §2.4
    m = P.ElevationMap(o)
    assert m.cells == 1000
    assert m.height(1.0, 1.0) is None and m.cell(1.0, 1.0)[1] == math.inf
    s = m.fuse_points(np.array([[1.005, 0.005, 0.3], [1.005, 0.005, 0.5]]), np.array([0.01, 0.01]))
    assert s.new_cells == 1 and s.fused_points == 2
    assert m.height(1.005, 0.005) == pytest.approx(0.4)  # one measurement per cell per call
    s = m.fuse_points(np.array([[1.005, 0.005, 0.6]]), np.array([0.01]))
    assert s.updated_cells == 1
    z, v = m.cell(1.005, 0.005)
    assert z == pytest.approx(0.5) and v == pytest.approx(0.005)  # Kalman of [17]
    with pytest.raises(ValueError, match="2 points but 1 variances"):
        m.fuse_points(np.zeros((2, 3)), np.zeros(1))
    h = m.heights
    assert h.shape == (1000, 1000) and np.isfinite(h).sum() == 1
    assert m.consistent()
    # the map is a HeightSource: the §4.2 sampler fills the holes along its lines
    for x in np.arange(0.0, 2.0, 0.01):
        m.fuse_points(np.array([[x, 0.4, 0.05], [x, -0.4, 0.05]]), np.array([1e-4, 1e-4]))
    sampler = sensing.ElevationSampler()
    values, sources = sampler.sample(np.array([0.0, 0.0, 0.3]), np.eye(3), m)
    assert np.all(np.isfinite(values))
    assert sampler.options.ground_z == pytest.approx(-0.30)
    # chassis 0.30 m above z = 0 and ground_z = -0.30: the 5 cm strips read 0.05 (float32 cells)
    np.testing.assert_allclose(values[:6], 0.05, atol=1e-6)


def test_mapper_builds_a_flat_map_of_flat_ground():
    terrain = D.HeightMap.flat(30.0, 20.0, 0.05, 0.0, -5.0, -10.0)
    mp = P.StereoMapper(terrain, [])
    assert mp.update(0.0, np.array([0.0, 0.0, 0.17]), np.eye(3))
    assert not mp.update(1.0, np.array([0.1, 0.0, 0.17]), np.eye(3))  # 0.5 Hz
    fr = mp.last_frame
    assert fr.points.shape[0] == fr.stats.fused_points + fr.stats.outside_map
    assert fr.stats.fused_points > 100000
    h = mp.map.heights
    known = h[np.isfinite(h)]
    assert known.size > 50000
    assert abs(np.median(known)) < 0.005 and np.sqrt(np.mean(known**2)) < 0.03


def _stereo_options(width=320, height=240):
    so = P.StereoMapperOptions()
    so.camera.width, so.camera.height = width, height  # smaller frames keep the test fast
    return so


def test_stereo_env_passes_check_env_and_uses_the_map():
    env = E.ErnestEnv("rockfield", terrain_source="stereo", stereo=_stereo_options())
    check_env(env, skip_render_check=True)
    obs, _ = env.reset(seed=2)
    assert obs.shape == (45,) and np.all(np.isfinite(obs))
    assert env.core.mapper is not None and env.core.mapper.frames == 1
    for _ in range(4):
        obs, *_ = env.step(np.array([1.0, 0.0, 0.0], np.float32))
    assert env.core.mapper.frames == 2 and np.all(np.isfinite(obs))
    truth = E.ErnestEnv("rockfield")
    truth.reset(seed=2)
    assert truth.core.mapper is None
    with pytest.raises(ValueError, match="terrain_source = 'lidar'"):
        E.ErnestEnv("rockfield", terrain_source="lidar")


def test_stereo_vector_env_steps():
    vec = E.ErnestVectorEnv(2, num_threads=2, scenario="step", terrain_source="stereo",
                            stereo=_stereo_options(), episode_length=1.5)
    obs, _ = vec.reset(seed=4)
    assert obs.shape == (2, 45)
    for _ in range(4):  # through an autoreset
        obs, r, term, trunc, _ = vec.step(np.tile([1.0, 0.0, 0.0], (2, 1)))
        assert np.all(np.isfinite(obs)) and np.all(np.isfinite(r))


def test_perception_command_writes_views(tmp_path, capsys):
    out = tmp_path / "perception"
    assert cli_main(["perception", "--scenario", "rockfield", "--out", str(out), "--frames", "2"]) == 0
    assert (out / "frame_0.png").stat().st_size > 10000 and (out / "frame_1.png").exists()
    lines = (out / "summary.csv").read_text().splitlines()
    assert lines[0].startswith("frame [-],points [-],cells [-],rms [m]")  # units in the header
    rms = [float(line.split(",")[3]) for line in lines[1:]]
    assert all(0.0 < r < 0.05 for r in rms)
    assert "RMS" in capsys.readouterr().out


def test_elevation_map_refuses_a_move_its_cell_indices_cannot_hold():
    em = P.ElevationMap()
    em.fuse_points(np.array([[0.0, 0.0, 0.0]]), np.array([1e-4]))
    em.move_to(1e6, 0.0)  # far but representable: the window simply moves
    for x, y in ((1e17, 0.0), (0.0, -1e18), (math.inf, 0.0)):
        with pytest.raises(ValueError, match="move_to"):
            em.move_to(x, y)
