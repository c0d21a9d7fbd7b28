"""The 3D viewer in a real browser: headless Chromium (Debian's chromium and chromium-driver,
installed by ./run test) opens a recorded RockField episode, waits for the scene and looks at the
pixels with the viewer's fixed camera: terrain colours fill the ground, the rover's orange chassis
is drawn where the camera projects the rover; pressing End on the time slider moves the rover to
its last recorded place on screen; the rover layer's check box hides and shows it.

With ERNEST_VIEWER_PICTURES=FOLDER the screenshots are also saved there (the README's pictures:
docs/pictures)."""

from __future__ import annotations

import os
import time

import gymnasium as gym
import numpy as np
import pytest

import ernest_cpp.envs  # noqa: F401

pytest.importorskip("viser")
pytest.importorskip("selenium")

from ernest_cpp.viewer import Player, RecordEpisode, browser  # noqa: E402
from ernest_cpp.viewer import geometry as G  # noqa: E402
from ernest_cpp.viewer.scene import CHASSIS_RGB  # noqa: E402

if browser.find_chromium() is None:
    pytest.skip("chromium and chromedriver are not installed (./run test installs them)",
                allow_module_level=True)

SIZE = (960, 600)
PANEL_X = 600  # the control panel floats over the right part of the view: look left of it


def chassis_mask(img: np.ndarray) -> np.ndarray:
    """Pixels of the chassis' orange (shaded by the lights): red high, green and blue well below."""
    r, g, b = (img[..., k].astype(int) for k in range(3))
    ref = np.array(CHASSIS_RGB)
    mask = (r > 120) & (r - g > 60) & (r - b > 90) & (g > b - 10) & (ref[0] > ref[1])
    mask[-80:, :80] = False  # the axes gizmo in the bottom-left corner has a red axis
    return mask


def terrain_mask(img: np.ndarray) -> np.ndarray:
    """Pixels of the elevation ramp (blue-grey through sand to pale), not the white page."""
    r, g, b = (img[..., k].astype(int) for k in range(3))
    not_white = (r + g + b) < 3 * 245
    earthy = (np.abs(r - g) < 70) & (np.abs(g - b) < 80) & ~((r - g > 60) & (r - b > 90))
    return not_white & earthy


def centroid(mask: np.ndarray) -> np.ndarray:
    v, u = np.nonzero(mask)
    return np.array([u.mean(), v.mean()])


def save(img, name):
    folder = os.environ.get("ERNEST_VIEWER_PICTURES")
    if folder:
        from PIL import Image

        os.makedirs(folder, exist_ok=True)
        Image.fromarray(img.astype(np.uint8)).save(os.path.join(folder, name))


@pytest.fixture(scope="module")
def viewer(tmp_path_factory):
    path = str(tmp_path_factory.mktemp("rec") / "rockfield.npz")
    env = RecordEpisode(gym.make("ernest/RockField-v0", episode_length=30.0), path)
    env.reset(seed=3)
    while True:
        _, _, term, trunc, _ = env.step(np.array([0.8, 0.1, 0.0]))
        if term or trunc:
            break
    player = Player(path, port=0)
    driver = browser.start_browser(SIZE)
    try:
        t0 = time.perf_counter()
        driver.get(player.url)
        first = browser.wait_for_scene(driver, timeout=120)
        print(f"scene drawn in {time.perf_counter() - t0:.1f} s")
        browser.dismiss_notices(driver)
        first = browser.wait_for_scene(driver, timeout=30)
        yield player, driver, first
    finally:
        driver.quit()
        player.close()


def expected_pixel(player, frame: int, shape) -> np.ndarray:
    eye, target, fov = player.camera
    f = player.recording.frames
    # the chassis body's centre: above the chassis frame origin
    pos = f["position"][frame] + G.quat_matrix(f["quaternion"][frame]) @ np.array([-0.04, 0, 0.33])
    h, w = shape
    return G.project(pos, eye, target, fov, w, h)[0]


def test_scene_shows_terrain_and_rover_where_expected(viewer):
    player, driver, img = viewer
    save(img, "viewer_rockfield_start.png")
    view = img[:, :PANEL_X]
    assert float(view.std()) > 10.0, "blank canvas"
    lower = view[img.shape[0] // 2:]
    assert terrain_mask(lower).mean() > 0.5, "the ground is not drawn in terrain colours"
    rover = chassis_mask(view)
    assert rover.sum() > 150, f"rover not drawn ({rover.sum()} chassis pixels)"
    expect = expected_pixel(player, 0, img.shape[:2])
    assert np.linalg.norm(centroid(rover) - expect) < 60, (centroid(rover), expect)
    assert player.clients() >= 1


def test_time_slider_moves_the_rover(viewer):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    player, driver, first = viewer
    start = centroid(chassis_mask(first[:, :PANEL_X]))
    last = len(player.recording) - 1
    for _ in range(3):  # the browser's own slider: scrub to the end of the episode
        slider = driver.find_elements(By.CSS_SELECTOR, "[role=slider]")[0]  # "time [s]"
        driver.execute_script("arguments[0].focus();", slider)
        slider.send_keys(Keys.END)
        deadline = time.monotonic() + 10
        while player.frame != last and time.monotonic() < deadline:
            time.sleep(0.2)
        if player.frame == last:
            break
    assert player.frame == last, "the slider did not reach the server"
    img = browser.wait_for_scene(driver, timeout=60)
    save(img, "viewer_rockfield_end.png")
    rover = chassis_mask(img[:, :PANEL_X])
    assert rover.sum() > 40, "rover not drawn at the end"
    end = centroid(rover)
    expect = expected_pixel(player, last, img.shape[:2])
    assert np.linalg.norm(end - start) > 40, (start, end)
    assert np.linalg.norm(end - expect) < 60, (end, expect)


def test_rover_layer_switches_off_and_on(viewer):
    from selenium.webdriver.common.by import By

    player, driver, _ = viewer
    player.scene.checkboxes["forces"].value = False  # the load arrows turn red under load
    # the check box whose row is labelled "rover" (the panel has hidden settings boxes too)
    rover = next(b for b in driver.find_elements(By.CSS_SELECTOR, "input[type=checkbox]")
                 if b.is_displayed() and driver.execute_script(
                     "let e = arguments[0]; while (e && !e.innerText) e = e.parentElement;"
                     "return e ? e.innerText.trim() : '';", b) == "rover")
    for on in (False, True):
        driver.execute_script("arguments[0].click();", rover)
        deadline = time.monotonic() + 10
        while player.scene.layers["rover"].visible is not on and time.monotonic() < deadline:
            time.sleep(0.1)
        assert player.scene.layers["rover"].visible is on
        time.sleep(1.0)  # the browser redraws
        img = browser.wait_for_scene(driver, timeout=60)
        drawn = chassis_mask(img[:, :PANEL_X]).sum()
        assert (drawn > 40) if on else (drawn < 5), (on, drawn)
    player.scene.checkboxes["forces"].value = True
