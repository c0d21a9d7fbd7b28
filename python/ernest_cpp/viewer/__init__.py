"""The operator's 3D view in a browser (viser; ``pip install 'ernest-cpp[viewer]'``).

- ``RecordEpisode(env, "ep.npz")`` (a Gymnasium wrapper) or ``record_episode(env, policy, path)``
  record an episode of any ernest environment; ``load_recording(path)`` reads one back.
- ``Player(path)`` serves a recording: terrain coloured by elevation, rocks and steps, the desired
  path, the rover's bodies, wheel loads as arrows, the track, each layer switchable; time series
  of wheel loads, gimbal yaw and roll, actions and power follow the time slider.
  ``ernest view RECORDING`` does the same from the command line.
- ``LiveViewer`` streams a running environment; ``gym.make(..., render_mode="human")`` uses it.

Recording needs only numpy; the servers import viser when they start.
"""

from .recording import (FRAME_FIELDS, EpisodeRecorder, RecordEpisode, Recording,  # noqa: F401
                        load_recording, record_episode, save_recording)


def __getattr__(name):  # the servers load viser only when used
    if name in ("Player", "LiveViewer"):
        from . import app

        return getattr(app, name)
    raise AttributeError(name)
