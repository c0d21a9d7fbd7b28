"""Headless Chromium (Debian's ``chromium`` and ``chromium-driver``, through Selenium) pointed at a
viewer: waits until the scene is drawn and takes a screenshot. The browser test and
``ernest view --screenshot`` use it."""

from __future__ import annotations

import io
import os
import shutil
import time

import numpy as np

CHROMIUM = ("chromium", "chromium-browser", "google-chrome")
DRIVERS = ("chromedriver", "chromium-driver")


def find_chromium() -> tuple[str, str] | None:
    """(browser, driver) paths, or None when either is missing."""
    browser = next((p for p in map(shutil.which, CHROMIUM) if p), None)
    driver = next((p for p in map(shutil.which, DRIVERS) if p), None)
    return (browser, driver) if browser and driver else None


def start_browser(size: tuple[int, int] = (1280, 800)):
    """A headless Chromium under Selenium, drawing WebGL in software (SwiftShader)."""
    found = find_chromium()
    if found is None:
        raise RuntimeError("headless screenshots need chromium and chromedriver "
                           "(Debian: apt-get install chromium chromium-driver)")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = found[0]
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist",
                f"--window-size={size[0]},{size[1]}", "--hide-scrollbars", "--mute-audio"):
        opts.add_argument(arg)
    return webdriver.Chrome(service=Service(found[1]), options=opts)


def grab(driver) -> np.ndarray:
    """The page as an (h, w, 3) uint8 array."""
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(driver.get_screenshot_as_png())).convert("RGB"))


def scene_drawn(img: np.ndarray) -> bool:
    """True once the 3D view shows more than its background: a good share of the left part of
    the window (the control panel is on the right) differs from white."""
    h, w, _ = img.shape
    view = img[h // 8: 7 * h // 8, : int(w * 0.7)].astype(int)
    return float(np.mean(np.abs(view - 255).sum(axis=2) > 30)) > 0.2


def wait_for_scene(driver, timeout: float = 60.0, settle: float = 1.0) -> np.ndarray:
    """Screenshots until the scene is drawn and two successive ones agree; returns the last."""
    t_end = time.monotonic() + timeout
    last = None
    while time.monotonic() < t_end:
        img = grab(driver)
        if scene_drawn(img):
            if last is not None and np.mean(np.abs(img.astype(int) - last)) < 1.0:
                return img
            last = img.astype(int)
        time.sleep(settle)
    raise TimeoutError(f"the viewer's scene was not drawn within {timeout:.0f} s")


def screenshot(url: str, path: str, size: tuple[int, int] = (1280, 800),
               timeout: float = 60.0) -> np.ndarray:
    """Open ``url`` in headless Chromium, wait for the scene, save a PNG to ``path``."""
    from PIL import Image

    driver = start_browser(size)
    try:
        driver.get(url)
        wait_for_scene(driver, timeout)
        if dismiss_notices(driver):  # e.g. "software WebGL": not part of the view
            time.sleep(0.5)
        img = wait_for_scene(driver, timeout)
    finally:
        driver.quit()
    folder = os.path.dirname(path)
    if folder:
        os.makedirs(folder, exist_ok=True)
    Image.fromarray(img.astype(np.uint8)).save(path)
    return img


def dismiss_notices(driver) -> int:
    """Close the viewer's pop-up notices (e.g. "software WebGL"); returns how many."""
    from selenium.webdriver.common.by import By

    n = 0
    for button in driver.find_elements(By.CSS_SELECTOR, ".mantine-Notification-root button"):
        try:
            button.click()
            n += 1
        except Exception:  # gone already
            pass
    return n
