"""Pose arithmetic for the viewer (numpy only): the bodies of the rover from a recorded frame,
the terrain mesh coloured by elevation, the obstacle boxes' orientations."""

from __future__ import annotations

import math

import numpy as np


def quat_mul(a, b) -> np.ndarray:
    """Hamilton product of (w, x, y, z) quaternions."""
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def quat_axis(axis: str, angle: float) -> np.ndarray:
    h = 0.5 * angle
    q = np.array([math.cos(h), 0.0, 0.0, 0.0])
    q["xyz".index(axis) + 1] = math.sin(h)
    return q


def quat_matrix(q) -> np.ndarray:
    w, x, y, z = np.asarray(q, dtype=np.float64) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def quat_zyx(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Rz(yaw) Ry(pitch) Rx(roll) as a quaternion (the obstacles' convention)."""
    return quat_mul(quat_mul(quat_axis("z", yaw), quat_axis("y", pitch)), quat_axis("x", roll))


#: wheel -> body carrying it: the bogie carries the front wheels, the chassis the rear ones
FRONT = (0, 1)


def rover_bodies(frame: dict, geometry: dict) -> dict:
    """World poses (position, wxyz) of the chassis, the bogie and the four wheels of one frame.

    The chassis frame is the simulator's (``RoverState.position``/``quaternion``: the rear axle
    centre); the bogie turns about the gimbal point by the gimbal yaw, then the roll (Rz Rx),
    as the simulator's joints do; each wheel sits at its recorded centre with the orientation of
    the body carrying it (the spin angle is not recorded: a wheel is round).
    """
    pos = np.asarray(frame["position"], dtype=np.float64)
    q = np.asarray(frame["quaternion"], dtype=np.float64)
    R = quat_matrix(q)
    g = np.asarray(geometry["gimbal_point"], dtype=np.float64)
    yaw, roll = (float(v) for v in frame["gimbal"])
    qb = quat_mul(q, quat_mul(quat_axis("z", yaw), quat_axis("x", roll)))
    bodies = {"chassis": (pos, q), "bogie": (pos + R @ g, qb)}
    for i, name in enumerate(("FL", "FR", "RL", "RR")):
        bodies[f"wheel_{name}"] = (np.asarray(frame["wheel_position"][i], dtype=np.float64),
                                   qb if i in FRONT else q)
    return bodies


def elevation_colours(z: np.ndarray) -> np.ndarray:
    """(n, 3) uint8 colours of heights ``z``: low blue-grey through sand to light brown-white
    (an earthy ramp with enough contrast to read steps and ripples)."""
    stops = np.array([[60, 80, 115], [125, 115, 90], [185, 150, 100], [225, 205, 165]], float)
    lo, hi = (float(v) for v in np.percentile(z, [2.0, 98.0]))  # a few peaks do not wash it out
    if hi - lo < 0.2:  # flat ground (a step's course): sand, not the ramp's ends
        mid = 0.5 * (lo + hi)
        lo, hi = mid - 0.1, mid + 0.1
    z = np.asarray(z, dtype=np.float64)
    u = np.clip((z - lo) / (hi - lo), 0.0, 1.0) if hi > lo else np.zeros_like(z)
    x = u * (len(stops) - 1)
    i = np.clip(np.floor(x).astype(int), 0, len(stops) - 2)
    f = (x - i)[..., None]
    return ((1 - f) * stops[i] + f * stops[i + 1]).astype(np.uint8)


def terrain_mesh(heights: np.ndarray, spacing: float, origin, max_cells: int = 200):
    """Vertices (n, 3), faces (m, 3) and vertex colours of the height map (x-major grid), thinned
    to at most ``max_cells`` per side."""
    h = np.asarray(heights, dtype=np.float32)
    step = max(1, int(math.ceil(max(h.shape) / max_cells)))
    h = h[::step, ::step]
    nx, ny = h.shape
    xs = origin[0] + spacing * step * np.arange(nx)
    ys = origin[1] + spacing * step * np.arange(ny)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    verts = np.stack([X.ravel(), Y.ravel(), h.ravel()], axis=1).astype(np.float32)
    idx = np.arange(nx * ny).reshape(nx, ny)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]).astype(np.uint32)
    return verts, faces, elevation_colours(h.ravel())


def path_points(path, heights: np.ndarray, spacing: float, origin, lift: float = 0.03):
    """(n, 3) points of the desired path line across the height map, ``lift`` above it."""
    x0, y0, heading = path
    h = np.asarray(heights)
    nx, ny = h.shape
    L = spacing * max(nx, ny) * 1.5
    s = np.linspace(-L, L, 600)
    x, y = x0 + s * math.cos(heading), y0 + s * math.sin(heading)
    i = np.round((x - origin[0]) / spacing).astype(int)
    j = np.round((y - origin[1]) / spacing).astype(int)
    inside = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
    return np.stack([x[inside], y[inside], h[i[inside], j[inside]] + lift], axis=1)


def project(points, eye, target, fov_y: float, width: int, height: int) -> np.ndarray:
    """Pixel coordinates (u right, v down) of world ``points`` (n, 3) seen by a pinhole camera at
    ``eye`` looking at ``target`` with +z up and vertical field of view ``fov_y`` [rad]: where
    the viewer's fixed camera draws them."""
    eye = np.asarray(eye, dtype=float)
    f = np.asarray(target, dtype=float) - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, [0.0, 0.0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    d = np.atleast_2d(np.asarray(points, dtype=float)) - eye
    x, y, z = d @ r, d @ u, d @ f
    k = 0.5 * height / math.tan(0.5 * fov_y)
    return np.stack([0.5 * width + k * x / z, 0.5 * height - k * y / z], axis=1)
