"""``ernest view RECORDING``: open a recorded episode in the browser's 3D view (time slider,
layers, wheel loads, gimbal angles, actions and power). Recordings come from
``ernest evaluate --record`` or ``ernest_cpp.viewer.RecordEpisode``. With ``--screenshot PNG``
it draws the view in headless Chromium at ``--time`` and exits instead of serving.
"""

from __future__ import annotations

import argparse
import math
import time


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--size {text!r}: give WIDTHxHEIGHT, e.g. 960x600") from None
    if not (200 <= w <= 4000 and 200 <= h <= 4000):
        raise argparse.ArgumentTypeError(f"--size {text!r}: width and height must be in [200, 4000]")
    return w, h


def _time(text: str) -> float:
    try:
        t = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--time {text!r} is not a number of seconds") from None
    if not math.isfinite(t):
        raise argparse.ArgumentTypeError(f"--time {text!r} must be finite")
    return t


def _port(text: str) -> int:
    try:
        p = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--port {text!r} is not an integer") from None
    if not 0 <= p <= 65535:
        raise argparse.ArgumentTypeError(f"--port {p} must be in [0, 65535] (0: any free port)")
    return p


def run(args: argparse.Namespace) -> int:
    from .recording import load_recording

    rec = load_recording(args.recording)  # a missing or damaged file: one line naming it
    if args.screenshot:
        from . import browser

        if browser.find_chromium() is None:
            raise ValueError("--screenshot needs chromium and chromedriver (Debian: apt-get "
                             "install chromium chromium-driver)")
    from .app import Player

    print(f"loading {args.recording}: {rec.meta.get('scenario', '?')}, {len(rec)} frames, "
          f"{rec.duration:.1f} s", flush=True)
    player = Player(rec, port=args.port, host=args.host)
    try:
        if args.time is not None:
            player.set_time(args.time)
        if args.screenshot:
            from . import browser

            print(f"drawing {player.url} in headless Chromium -> {args.screenshot}", flush=True)
            browser.screenshot(player.url, args.screenshot, size=args.size)
            print(f"wrote {args.screenshot}")
            return 0
        print(f"ernest view: open {player.url} in a browser (Ctrl-C stops)", flush=True)
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        return 0
    finally:
        player.close()


def add_parser(sub) -> None:
    p = sub.add_parser("view", help="open a recorded episode in the browser's 3D view",
                       description=__doc__)
    p.add_argument("recording", help="recording file (.npz) from ernest evaluate --record")
    p.add_argument("--port", type=_port, default=8080, help="HTTP port (default 8080; 0: any free)")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1; 0.0.0.0 for other machines)")
    p.add_argument("--time", type=_time, default=None, help="start at this time [s]")
    p.add_argument("--screenshot", metavar="PNG", default=None,
                   help="draw the view in headless Chromium, write PNG and exit")
    p.add_argument("--size", type=_size, default=(960, 600),
                   help="screenshot size WIDTHxHEIGHT (default 960x600)")
    p.set_defaults(func=run)


def main(**options) -> int:
    """``ernest view`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest view --help``), checked as there (``cli.run``), e.g.
    ``main(recording="ep.npz", screenshot="view.png", time=20)``; without ``screenshot`` it
    serves until Ctrl-C. Returns the exit status; errors raise."""
    from ..cli import run as run_command

    return run_command("view", **options)
