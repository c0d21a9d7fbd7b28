"""rgb_array rendering (top and side views) and episode recording to GIF or MP4."""

from __future__ import annotations

import io
import math
import os

import numpy as np

_FIG = {}


def _figure():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if "fig" not in _FIG:
        _FIG["fig"], _FIG["axes"] = plt.subplots(1, 2, figsize=(10, 4.2), dpi=80,
                                                 gridspec_kw={"width_ratios": [1.25, 1]})
    return _FIG["fig"], _FIG["axes"]


def _rot(yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s], [s, c]])


def render_frame(env) -> np.ndarray:
    """Top view (terrain, rocks, path, rover with wheel loads, elevation samples) and side view
    (terrain profile along the path and the rover) of the current state, as an RGB array."""
    fig, (top, side) = _figure()
    top.clear()
    side.clear()
    sc = env.core.scenario
    st = env.core.state
    pos = np.asarray(st.position)
    yaw = st.yaw
    h = np.asarray(sc.heights)
    ox, oy = sc.origin
    extent = [ox, ox + sc.spacing * (h.shape[0] - 1), oy, oy + sc.spacing * (h.shape[1] - 1)]
    # window of 8 m around the rover
    x0, x1 = pos[0] - 3.0, pos[0] + 5.0
    y0, y1 = pos[1] - 3.0, pos[1] + 3.0
    top.imshow(h.T, origin="lower", extent=extent, cmap="copper", alpha=0.85)
    for o in np.asarray(sc.obstacles):
        cx, cy, _, lx, ly, _, oyaw = o[:7]
        corners = np.array([[-lx, -ly], [lx, -ly], [lx, ly], [-lx, ly], [-lx, -ly]]) / 2
        c = corners @ _rot(oyaw).T + [cx, cy]
        top.fill(c[:, 0], c[:, 1], color="0.55", edgecolor="0.2", lw=0.6)
    p = sc.path
    d = np.array([math.cos(p.heading), math.sin(p.heading)])
    line = np.array([[p.x0, p.y0] - 30 * d, [p.x0, p.y0] + 30 * d])
    top.plot(line[:, 0], line[:, 1], "--", color="tab:blue", lw=1.2, label="desired path")
    traj = np.array([s["position"][:2] for s in getattr(env, "history", [])] or [pos[:2]])
    top.plot(traj[:, 0], traj[:, 1], color="white", lw=1.0)
    wp = np.asarray(st.wheel_position)
    loads = np.asarray(st.wheel_load)
    body = np.array([[0.43, 0.4], [0.43, -0.4], [-0.43, -0.4], [-0.43, 0.4], [0.43, 0.4]])
    b = body @ _rot(yaw).T + pos[:2]
    top.plot(b[:, 0], b[:, 1], color="k", lw=1)
    sca = top.scatter(wp[:, 0], wp[:, 1], c=loads, cmap="viridis", vmin=0, vmax=300, s=60,
                      edgecolors="k", zorder=5)
    pts = np.asarray(env.core.elevation_points) @ _rot(yaw).T + pos[:2]
    top.scatter(pts[:, 0], pts[:, 1], s=8, color="tab:cyan", zorder=6, label="elevation samples")
    top.set_xlim(x0, x1)
    top.set_ylim(y0, y1)
    top.set_aspect("equal")
    top.set_title(f"{sc.name}  t = {st.time:.1f} s", fontsize=9)
    top.legend(loc="upper left", fontsize=7)
    if "cbar" not in _FIG:
        _FIG["cbar"] = fig.colorbar(sca, ax=top, fraction=0.035, label="wheel load [N]")
    # side view along the path direction through the rover
    s = np.linspace(-3.0, 5.0, 200)
    xs, ys = pos[0] + s * d[0], pos[1] + s * d[1]
    zs = np.array([sc.height(x, y) for x, y in zip(xs, ys)])
    side.fill_between(s, zs, zs.min() - 0.3, color="#c2a27a")
    along = (wp[:, :2] - pos[:2]) @ d
    side.scatter(along, wp[:, 2], s=80, facecolors="none", edgecolors="k")
    side.plot([along.min(), along.max()], [pos[2], pos[2]], color="k", lw=3)
    side.set_xlim(-3, 5)
    side.set_ylim(zs.min() - 0.3, max(zs.max(), pos[2]) + 0.6)
    side.set_aspect("equal")
    side.set_title(f"side view  yaw {math.degrees(st.gimbal_yaw):+.0f} deg, "
                   f"roll {math.degrees(st.gimbal_roll):+.0f} deg", fontsize=9)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="rgba", dpi=80)
    w, hgt = fig.canvas.get_width_height()
    img = np.frombuffer(buf.getvalue(), dtype=np.uint8).reshape(hgt, w, 4)[..., :3]
    return img.copy()


def write_animation(frames: list[np.ndarray], path: str, fps: float = 4.0) -> str:
    """Write frames to ``path`` (.gif with Pillow, .mp4 if imageio-ffmpeg is installed), atomically."""
    if not frames:
        raise ValueError("no frames to write")
    tmp = path + ".tmp" + os.path.splitext(path)[1]
    if path.endswith(".mp4"):
        import imageio.v2 as imageio  # optional: pip install imageio imageio-ffmpeg

        imageio.mimwrite(tmp, frames, fps=fps)
    elif path.endswith(".gif"):
        from PIL import Image

        imgs = [Image.fromarray(f) for f in frames]
        imgs[0].save(tmp, save_all=True, append_images=imgs[1:], duration=int(1000 / fps), loop=0)
    else:
        raise ValueError(f"unsupported animation format for {path!r}: use .gif or .mp4")
    os.replace(tmp, path)
    return path


def record_episode(env, policy, path: str, seed: int = 0, every: int = 1, max_steps: int = 10_000,
                   fps: float = 4.0) -> dict:
    """Run one episode of ``policy(obs, env) -> action`` and write an animation of it."""
    if hasattr(policy, "reset"):
        policy.reset()
    obs, _ = env.reset(seed=seed)
    frames = [render_frame(env)]
    for k in range(max_steps):
        obs, _, term, trunc, _ = env.step(policy(obs, env))
        if k % every == 0 or term or trunc:
            frames.append(render_frame(env))
        if term or trunc:
            break
    write_animation(frames, path, fps)
    return env.metrics
