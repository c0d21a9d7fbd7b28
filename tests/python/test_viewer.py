"""The 3D viewer without a browser: recordings (write, read, refuse damaged files), the rover's
bodies posed from the recorded state, the playback server, ``ernest view`` / ``ernest evaluate
--record`` on the command line, the live view (``render_mode="human"``) never holding up ``step``,
and Gymnasium's RecordVideo on the environments' rgb_array frames."""

from __future__ import annotations

import os
import time

import gymnasium as gym
import numpy as np
import pytest

import ernest_cpp.envs  # noqa: F401  (registers the ids)
from ernest_cpp import cli
from ernest_cpp.viewer import (FRAME_FIELDS, EpisodeRecorder, RecordEpisode, load_recording,
                               record_episode)
from ernest_cpp.viewer import geometry as G

pytest.importorskip("viser")

FORWARD = np.array([0.6, 0.1, 0.2])


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    path = str(tmp_path_factory.mktemp("rec") / "rock.npz")
    env = RecordEpisode(gym.make("ernest/RockField-v0", episode_length=8.0), path)
    env.reset(seed=3)
    while True:
        _, _, term, trunc, _ = env.step(FORWARD)
        if term or trunc:
            break
    assert env.written == [path]
    return path, env.unwrapped


def test_recording_holds_scene_and_frames(recording):
    path, env = recording
    rec = load_recording(path)
    n = len(rec)
    assert n == 17  # reset + 16 steps of 0.5 s
    for name, (shape, _) in FRAME_FIELDS.items():
        assert rec.frames[name].shape == (n, *shape), name
    assert np.allclose(rec.frames["time"], np.arange(n) * 0.5)
    sc = env.core.scenario
    assert rec.heights.shape == np.asarray(sc.heights).shape
    assert rec.obstacles.shape == (np.asarray(sc.obstacles).shape[0], 9)
    assert rec.meta["scenario"] == "rockfield" and rec.meta["env_id"] == "ernest/RockField-v0"
    st = env.core.state  # the last frame is the episode's last state
    assert np.allclose(rec.frames["position"][-1], st.position, atol=1e-6)
    assert np.allclose(rec.frames["wheel_load"][-1], st.wheel_load, rtol=1e-5, atol=1e-3)
    assert np.allclose(rec.frames["action"][1:], FORWARD, atol=1e-6)
    assert os.path.getsize(path) < 20e6


def test_bodies_posed_from_state_match_the_wheels(recording):
    """The bogie posed from the chassis and the gimbal angles carries the front wheels where the
    simulator has them, the chassis the rear ones (the recorded wheel centres)."""
    path, env = recording
    rec = load_recording(path)
    geo = rec.meta["geometry"]
    p = env.params
    assert np.ptp(rec.frames["gimbal"][:, 0]) > 0.05  # the gimbal moved: a real check
    for k in range(len(rec)):
        frame = {name: v[k] for name, v in rec.frames.items()}
        bodies = G.rover_bodies(frame, geo)
        for i, name in enumerate(("FL", "FR", "RL", "RR")):
            carrier = "bogie" if i in G.FRONT else "chassis"
            pos, q = bodies[carrier]
            local = np.asarray(p.wheel_centre(i)) - (np.asarray(geo["gimbal_point"])
                                                     if carrier == "bogie" else 0.0)
            expected = pos + G.quat_matrix(q) @ local
            assert np.allclose(expected, frame["wheel_position"][i], atol=2e-3), (k, name)


def test_missing_and_damaged_recordings_are_named(tmp_path):
    missing = tmp_path / "nothing.npz"
    with pytest.raises(FileNotFoundError) as exc:
        load_recording(str(missing))
    assert exc.value.filename == str(missing)
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip file at all" * 10)
    with pytest.raises(ValueError, match="junk.npz.*not a readable ernest recording"):
        load_recording(str(junk))
    other = tmp_path / "other.npz"
    np.savez(other, a=np.zeros(3))
    with pytest.raises(ValueError, match="other.npz.*not an ernest recording"):
        load_recording(str(other))
    with pytest.raises(ValueError, match="recording"):
        load_recording(None)


def test_truncated_recording_is_named(recording, tmp_path):
    path, _ = recording
    cut = tmp_path / "cut.npz"
    data = open(path, "rb").read()
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(ValueError, match="cut.npz"):
        load_recording(str(cut))


def test_view_command_names_a_bad_file(tmp_path, capsys):
    assert cli.main(["view", str(tmp_path / "missing.npz")]) == 2
    err = capsys.readouterr().err
    assert "missing.npz" in err and "no such recording" in err
    bad = tmp_path / "bad.npz"
    bad.write_text("garbage")
    assert cli.main(["view", str(bad)]) == 2
    assert "bad.npz" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        cli.main(["view", str(bad), "--port", "70000"])
    assert "--port" in capsys.readouterr().err


def test_player_serves_and_scrubs(recording):
    from ernest_cpp.viewer import Player

    path, _ = recording
    t0 = time.perf_counter()
    with Player(path, port=0) as player:
        assert time.perf_counter() - t0 < 5.0  # opening a recording
        assert player.frame == 0
        assert player.set_time(2.0) == 4
        player.speed.value = 4.0
        player.play.value = True  # plays on by itself: 4 s of episode a second
        deadline = time.monotonic() + 10.0
        while player.frame <= 6 and time.monotonic() < deadline:
            time.sleep(0.05)
        player.play.value = False
        assert player.frame > 6
        assert player.set_time(1e6) == len(player.recording) - 1
        assert player.slider.value == pytest.approx(player.recording.frames["time"][-1])
        for layer in ("terrain", "rover", "forces"):
            player.scene.checkboxes[layer].value = False
            assert player.scene.layers[layer].visible is False
        with pytest.raises(ValueError, match="t = nan"):
            player.set_time(float("nan"))
    with pytest.raises(ValueError, match="port"):
        Player(path, port=-1)


def test_evaluate_record_writes_recordings(tmp_path, capsys):
    out = tmp_path / "report"
    assert cli.main(["evaluate", "--out", str(out), "--scenario", "wheel_step", "--no-video",
                     "--record"]) == 0
    assert f"wrote 2 recordings to {out / 'recordings'}" in capsys.readouterr().out
    files = sorted(os.listdir(out / "recordings"))
    assert files == ["wheel_high_step_m90_crawling_gait.npz", "wheel_high_step_m90_passive_bogie.npz"]
    rec = load_recording(str(out / "recordings" / files[0]))
    assert rec.meta["scenario"] == "wheel_step" and len(rec) > 10
    assert rec.obstacles.shape[0] >= 1  # the step, as a box


def test_human_render_never_waits_for_the_browser(monkeypatch):
    """With the viewer's sending stuck (a closed or slow browser), steps run at full speed and
    only the newest state waits to be sent."""
    from ernest_cpp.viewer import app

    sent = []

    def stuck(self, static, row):
        sent.append(row["time"])
        time.sleep(2.0)

    monkeypatch.setattr(app.LiveViewer, "_send", stuck)
    monkeypatch.setenv("ERNEST_VIEWER_PORT", "0")
    env = gym.make("ernest/Flat-v0", render_mode="human", episode_length=10.0)
    plain = gym.make("ernest/Flat-v0", episode_length=10.0)
    try:
        for e in (env, plain):
            e.reset(seed=0)
        t0 = time.perf_counter()
        for _ in range(20):
            env.step(FORWARD)
        t_human = time.perf_counter() - t0
        t0 = time.perf_counter()
        for _ in range(20):
            plain.step(FORWARD)
        t_plain = time.perf_counter() - t0
        viewer = env.unwrapped._viewer
        assert viewer.pushed == 21
        assert len(sent) <= 2  # the first frame is still being "sent"
        assert t_human < t_plain + 0.5, (t_human, t_plain)
    finally:
        env.close()
        plain.close()
    assert env.unwrapped._viewer is None


def test_human_render_streams_frames():
    os.environ.setdefault("ERNEST_VIEWER_PORT", "0")
    env = gym.make("ernest/RockField-v0", render_mode="human", episode_length=3.0)
    try:
        env.reset(seed=1)
        for _ in range(6):
            env.step(FORWARD)
        viewer = env.unwrapped._viewer
        deadline = time.monotonic() + 20.0
        while viewer.sent == 0 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert viewer.sent >= 1 and viewer.scene is not None
        assert env.render() is None
    finally:
        env.close()


def test_record_video_on_rgb_array(tmp_path):
    pytest.importorskip("moviepy")
    env = gym.make("ernest/Flat-v0", render_mode="rgb_array", episode_length=2.0)
    env = gym.wrappers.RecordVideo(env, str(tmp_path), episode_trigger=lambda k: True,
                                   disable_logger=True)
    env.reset(seed=0)
    while True:
        _, _, term, trunc, _ = env.step(FORWARD)
        if term or trunc:
            break
    env.close()
    videos = [f for f in os.listdir(tmp_path) if f.endswith(".mp4")]
    assert videos and os.path.getsize(tmp_path / videos[0]) > 1000


def test_recorder_refuses_other_envs_and_bad_paths():
    with pytest.raises(ValueError, match="env = .* not an ernest environment"):
        EpisodeRecorder(gym.make("CartPole-v1"))
    env = gym.make("ernest/Flat-v0")
    with pytest.raises(ValueError, match="path"):
        RecordEpisode(env, "")
    with pytest.raises(ValueError, match="policy"):
        record_episode(env, "not callable", "x.npz")


def test_walker_cycle_recording(tmp_path):
    """A FootFall gait cycle executed in ODE as a recording: each frame's legs are the model's
    link capsules at that frame, three or more feet always on the ground, the steps in order, the
    stability map cells and planned leg paths of every step kept; the player shows it."""
    from ernest_cpp import footfall_cycle as FC
    from ernest_cpp import walker as W
    from ernest_cpp.viewer import Player, save_recording
    from ernest_cpp.viewer.walker import cycle_recording, convex_hull

    model = W.WalkerModel(W.sdm_b_parameters())
    boxes, terrain, _ = FC.rock_world(model, seed=3, rocks=20)  # small and coarse: quick
    r = FC.run(model, terrain, boxes, FC.cycle_options(cell=0.05, frame_interval=0.5))
    path = save_recording(cycle_recording(model, r, boxes, terrain, seed=3),
                          str(tmp_path / "walker.npz"))
    rec = load_recording(path)
    assert rec.kind == "walker" and len(rec) == len(r.frame_time) > 10
    k = len(rec) // 2
    caps = model.capsules(np.asarray(r.frame_body[k]), np.asarray(r.frame_q[k]))
    assert np.allclose(rec.frames["links"][k], [[c.p0, c.p1] for c in caps], atol=1e-5)
    stance = rec.frames["stance"].sum(axis=1)
    assert stance.min() >= 3 and stance.max() == model.legs
    assert np.all(np.diff(rec.frames["step"]) >= 0) and rec.frames["step"][-1] == len(r.steps) - 1
    cells = rec.static["cells"]
    assert set(np.unique(cells[:, 0]).astype(int)) == set(range(len(r.steps)))
    assert set(np.unique(cells[:, 3]).astype(int)) <= {1, 2}
    assert rec.static["paths"].shape[1] == 4 and len(rec.static["paths"]) > 0
    assert rec.obstacles.shape == (len(boxes), 9)
    assert sorted(convex_hull(np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]]))) == [0, 1, 2, 3]
    with Player(path, port=0) as player:
        player.set_time(rec.frames["time"][-1])
        assert player.frame == len(rec) - 1
        player.scene.checkboxes["stability map"].value = False


def test_footfall_takes_record():
    parser, sub = cli.build_parser()
    args = parser.parse_args(["footfall", "--record"])
    assert args.record is True


def test_live_view_port_from_the_environment(monkeypatch):
    from ernest_cpp.viewer.app import LiveViewer

    for bad in ("http", "-1", "70000"):
        monkeypatch.setenv("ERNEST_VIEWER_PORT", bad)
        with pytest.raises(ValueError, match="ERNEST_VIEWER_PORT"):
            LiveViewer.from_environment()
    with pytest.raises(ValueError, match="max_fps"):
        LiveViewer(port=0, max_fps=0)


def test_view_from_python_draws_a_screenshot_or_names_the_file(recording, tmp_path):
    from ernest_cpp.viewer import browser
    from ernest_cpp.viewer.command import main

    with pytest.raises(FileNotFoundError, match="no such recording"):
        main(recording=str(tmp_path / "none.npz"), screenshot=str(tmp_path / "x.png"))
    if browser.find_chromium() is None:
        pytest.skip("chromium and chromedriver are not installed (./run test installs them)")
    path, _ = recording
    png = tmp_path / "view.png"
    assert main(recording=path, screenshot=str(png), time=4.0, port=0, size="800x500") == 0
    from PIL import Image

    img = np.asarray(Image.open(png).convert("RGB"))
    assert img.shape[1] == 800 and browser.scene_drawn(img)
