"""Preallocated ring replay buffer with O(1) uniform sampling and FTS noise injection (seed 004 §4.2).

Stored transitions are (s, a, r, s', terminated) in float32. ``sample`` gathers a minibatch by fancy
indexing (a copy), then adds fresh Gaussian noise to the configured observation components of both
s and s' (independent draws): "this noise is resampled each time a transition is drawn, so that a
single stored transition can be reused multiple times with different noise realizations" (§4.2).
The stored data are never modified.

Save/load: a directory of ``.npy`` chunks per field (storage order, ``chunk_rows`` rows each, so a
loaded buffer samples exactly like the saved one)
plus a checksummed manifest (see :mod:`.storage`), written atomically. ``last_n`` extracts the most
recent transitions and ``merge`` pools several buffers (consolidation, §4.6).
"""

from __future__ import annotations

import os

import numpy as np

from .storage import AtomicDir, CorruptFileError, read_manifest

FIELDS = ("obs", "act", "rew", "next_obs", "done")
FORMAT_VERSION = 1


class ReplayBuffer:
    def __init__(self, capacity: int, obs_dim: int, act_dim: int):
        if capacity < 1 or obs_dim < 1 or act_dim < 1:
            raise ValueError(f"replay buffer: capacity = {capacity}, obs_dim = {obs_dim}, act_dim = "
                             f"{act_dim} must all be >= 1")
        self.capacity, self.obs_dim, self.act_dim = int(capacity), int(obs_dim), int(act_dim)
        self.obs = np.zeros((self.capacity, obs_dim), np.float32)
        self.act = np.zeros((self.capacity, act_dim), np.float32)
        self.rew = np.zeros(self.capacity, np.float32)
        self.next_obs = np.zeros((self.capacity, obs_dim), np.float32)
        self.done = np.zeros(self.capacity, np.float32)
        self.ptr = 0  # next write position
        self.size = 0
        self.total_added = 0  # transitions ever added (ptr == total_added % capacity)
        self.noise_idx = np.zeros(0, np.int64)
        self.noise_std = np.zeros(0, np.float32)

    def __len__(self) -> int:
        return self.size

    # ------------------------------------------------------------------ noise
    def set_noise(self, indices, std) -> None:
        """Gaussian noise std (normalised units) added on sampling to obs[:, indices] and
        next_obs[:, indices]. Empty indices disable it."""
        idx = np.asarray(indices, dtype=np.int64).reshape(-1)
        sd = np.broadcast_to(np.asarray(std, dtype=np.float32), idx.shape).copy()
        if idx.size and (idx.min() < 0 or idx.max() >= self.obs_dim):
            raise ValueError(f"noise indices must lie in [0, {self.obs_dim}), got "
                             f"[{idx.min()}, {idx.max()}]")
        if len(np.unique(idx)) != len(idx):
            raise ValueError("noise indices must be unique")
        if np.any(~np.isfinite(sd)) or np.any(sd < 0):
            raise ValueError("noise std must be finite and >= 0")
        self.noise_idx, self.noise_std = idx, sd

    # ------------------------------------------------------------------ add / sample
    def add(self, obs, act, rew, next_obs, done) -> None:
        """Add one transition or a batch (leading dimension = number of transitions)."""
        obs = np.asarray(obs, np.float32).reshape(-1, self.obs_dim)
        n = obs.shape[0]
        act = np.asarray(act, np.float32).reshape(n, self.act_dim)
        rew = np.asarray(rew, np.float32).reshape(n)
        next_obs = np.asarray(next_obs, np.float32).reshape(n, self.obs_dim)
        done = np.asarray(done, np.float32).reshape(n)
        for name, x in (("obs", obs), ("act", act), ("rew", rew), ("next_obs", next_obs),
                        ("done", done)):
            if not np.isfinite(x).all():  # one NaN reward would poison the critic for good
                row = int(np.argwhere(~np.isfinite(x))[0][0])
                raise ValueError(f"ReplayBuffer.add: {name} of transition {row} of {n} is not "
                                 f"finite")
        if n > self.capacity:  # only the last `capacity` can survive
            obs, act, rew, next_obs, done = (x[-self.capacity:] for x in
                                             (obs, act, rew, next_obs, done))
            self.total_added += n - self.capacity
            self.ptr = (self.ptr + n - self.capacity) % self.capacity
            n = self.capacity
        idx = (self.ptr + np.arange(n)) % self.capacity
        self.obs[idx], self.act[idx], self.rew[idx] = obs, act, rew
        self.next_obs[idx], self.done[idx] = next_obs, done
        self.ptr = (self.ptr + n) % self.capacity
        self.size = min(self.size + n, self.capacity)
        self.total_added += n

    def sample(self, batch_size: int, rng: np.random.Generator, noise: bool = True,
               rows: dict | None = None) -> dict:
        """``rows``: further per-transition arrays (one entry per stored row) drawn with the
        same indices into the batch under their keys (e.g. ``anchor_mask``)."""
        if self.size == 0:
            raise ValueError("cannot sample from an empty replay buffer")
        i = rng.integers(0, self.size, size=batch_size)
        batch = {"obs": self.obs[i], "act": self.act[i], "rew": self.rew[i],
                 "next_obs": self.next_obs[i], "done": self.done[i]}
        for k, v in (rows or {}).items():
            batch[k] = v[i]
        if noise and self.noise_idx.size:
            k = self.noise_idx.size
            z = rng.standard_normal((2, batch_size, k), dtype=np.float32) * self.noise_std
            batch["obs"][:, self.noise_idx] += z[0]
            batch["next_obs"][:, self.noise_idx] += z[1]
        return batch

    # ------------------------------------------------------------------ views
    def _chrono_index(self) -> np.ndarray:
        """Indices of the stored transitions from oldest to newest."""
        if self.size < self.capacity:
            return np.arange(self.size)
        return (self.ptr + np.arange(self.capacity)) % self.capacity

    def chronological(self, start: int = 0, stop: int | None = None) -> dict:
        """Copies of the fields for chronological positions [start, stop) (0 = oldest)."""
        idx = self._chrono_index()[start:stop]
        return {f: getattr(self, f)[idx] for f in FIELDS}

    def last_n(self, n: int, capacity: int | None = None) -> "ReplayBuffer":
        """A new buffer holding the most recent min(n, size) transitions, in order."""
        if n < 1:
            raise ValueError(f"last_n: n = {n} must be >= 1")
        k = min(int(n), self.size)
        out = ReplayBuffer(capacity or max(k, 1), self.obs_dim, self.act_dim)
        if k:
            out.add(**self.chronological(self.size - k))
        out.set_noise(self.noise_idx, self.noise_std)
        return out

    @staticmethod
    def merge(buffers: list["ReplayBuffer"], capacity: int | None = None) -> "ReplayBuffer":
        """Pool several buffers (each in its chronological order, one after the other)."""
        if not buffers:
            raise ValueError("merge: no buffers given")
        dims = {(b.obs_dim, b.act_dim) for b in buffers}
        if len(dims) != 1:
            raise ValueError(f"merge: buffers have different (obs_dim, act_dim): {sorted(dims)}")
        total = sum(b.size for b in buffers)
        cap = capacity or max(total, 1)
        if cap < total:
            raise ValueError(f"merge: {total} transitions do not fit a capacity of {cap}; extract "
                             f"the most recent ones of each buffer first (last_n)")
        out = ReplayBuffer(cap, *dims.pop())
        for b in buffers:
            if b.size:
                out.add(**b.chronological())
        out.set_noise(buffers[0].noise_idx, buffers[0].noise_std)
        return out

    # ------------------------------------------------------------------ persistence
    def save(self, path: str, chunk_rows: int = 1 << 16) -> None:
        meta = {"format": FORMAT_VERSION, "capacity": self.capacity, "size": self.size,
                "total_added": self.total_added, "ptr": self.ptr, "obs_dim": self.obs_dim,
                "act_dim": self.act_dim, "chunk_rows": int(chunk_rows),
                "noise_idx": self.noise_idx.tolist(), "noise_std": self.noise_std.tolist()}
        with AtomicDir(path, "replay_buffer", meta) as tmp:
            for f in FIELDS:
                os.makedirs(os.path.join(tmp, f))
                arr = getattr(self, f)
                for c, start in enumerate(range(0, self.size, chunk_rows)):
                    np.save(os.path.join(tmp, f, f"{c:06d}.npy"),
                            arr[start:min(start + chunk_rows, self.size)], allow_pickle=False)

    @classmethod
    def load(cls, path: str, capacity: int | None = None, verify: bool = True) -> "ReplayBuffer":
        """Load a saved buffer. ``capacity`` (default: the saved one) may differ; if it is smaller
        than the stored size, the most recent transitions are kept. A chunk holding a NaN or an
        infinity is refused (CorruptFileError naming the chunk file), checksums or not."""
        man = read_manifest(path, "replay_buffer", verify)
        m = man.get("meta", {})
        try:
            if m["format"] != FORMAT_VERSION:
                raise CorruptFileError(f"{path}: buffer format {m['format']}, this version reads "
                                       f"{FORMAT_VERSION}")
            size, cr, ptr = int(m["size"]), int(m["chunk_rows"]), int(m["ptr"])
            saved_cap, total = int(m["capacity"]), int(m["total_added"])
            buf = cls(capacity or saved_cap, int(m["obs_dim"]), int(m["act_dim"]))
        except (KeyError, TypeError) as exc:
            raise CorruptFileError(f"{path}: manifest lacks or mangles field {exc}") from None
        n_chunks = -(-size // cr) if size else 0
        data = {}
        for f in FIELDS:
            parts = []
            for c in range(n_chunks):
                p = os.path.join(path, f, f"{c:06d}.npy")
                try:
                    parts.append(np.load(p, allow_pickle=False))
                except FileNotFoundError:
                    raise CorruptFileError(f"{p}: chunk missing") from None
                except ValueError as exc:
                    raise CorruptFileError(f"{p}: unreadable chunk ({exc})") from None
                if parts[-1].dtype.kind not in "fiub":
                    raise CorruptFileError(f"{p}: holds {parts[-1].dtype} values, expected "
                                           f"numbers")
                bad = ~np.isfinite(parts[-1])
                if bad.any():  # NaN/inf would poison every update that samples it
                    at = np.argwhere(bad)[0]
                    row = c * cr + int(at[0])
                    raise CorruptFileError(
                        f"{p}: non-finite {f} value {float(parts[-1][tuple(at)])} at stored row "
                        f"{row}{f', component {int(at[1])}' if at.size > 1 else ''} "
                        f"({int(bad.sum())} non-finite values in this chunk); a replay buffer "
                        f"must hold finite values only")
            arr = np.concatenate(parts) if parts else np.zeros((0,))
            width = {"obs": buf.obs_dim, "next_obs": buf.obs_dim, "act": buf.act_dim}.get(f)
            expected = (size, width) if width else (size,)
            if arr.shape != expected and not (size == 0):
                raise CorruptFileError(f"{path}/{f}: shape {arr.shape}, expected {expected}")
            data[f] = arr
        if not (0 <= size <= saved_cap and 0 <= ptr < saved_cap and size <= total):
            raise CorruptFileError(f"{path}: inconsistent size {size} / ptr {ptr} / capacity "
                                   f"{saved_cap} / total {total}")
        if buf.capacity == saved_cap:  # identical storage layout: sampling continues exactly
            for f in FIELDS:
                getattr(buf, f)[:size] = data[f]
            buf.size, buf.ptr, buf.total_added = size, ptr, total
        elif size:
            order = np.arange(size) if size < saved_cap else (ptr + np.arange(size)) % saved_cap
            buf.add(**{f: data[f][order] for f in FIELDS})
            buf.total_added = total
        buf.set_noise(m.get("noise_idx", []), m.get("noise_std", []))
        return buf
