"""Atomic, checksummed on-disk directories (replay buffers, checkpoints).

A stored object is a directory holding data files and ``manifest.json`` (written last) that lists
every file with its size and SHA-256. Writing goes to a temporary sibling directory that is renamed
into place only when complete, so a crash never leaves a half-written directory under the final
name. Reading verifies the manifest and every checksum and raises :class:`CorruptFileError` (a
ValueError) naming the file and the problem.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import uuid

MANIFEST = "manifest.json"
# AtomicDir's temporaries: ".NAME.tmp-XXXXXXXX" while writing, "NAME.old-XXXXXXXX" while replacing.
_STALE = re.compile(r"^(\..+\.tmp|.+\.old)-[0-9a-f]{8}$")


class CorruptFileError(ValueError):
    """A stored buffer/checkpoint is missing, truncated, altered or of the wrong format."""


def sha256_file(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 22), b""):
            h.update(block)
    return h.hexdigest()


def _fsync_dir(path: str) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


class AtomicDir:
    """Context manager: ``with AtomicDir(final) as tmp: write files into tmp`` then, on success,
    the manifest is written and ``tmp`` replaces ``final``."""

    def __init__(self, final: str, kind: str, meta: dict | None = None):
        self.final = os.path.abspath(final)
        self.kind, self.meta = kind, dict(meta or {})
        parent = os.path.dirname(self.final)
        os.makedirs(parent, exist_ok=True)
        self.tmp = os.path.join(parent, f".{os.path.basename(self.final)}.tmp-{uuid.uuid4().hex[:8]}")

    def __enter__(self) -> str:
        os.makedirs(self.tmp)
        return self.tmp

    def __exit__(self, exc_type, exc, tb):
        if exc_type is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
            return False
        files = {}
        for root, _, names in os.walk(self.tmp):
            for n in sorted(names):
                p = os.path.join(root, n)
                with open(p, "rb+") as fh:
                    os.fsync(fh.fileno())
                rel = os.path.relpath(p, self.tmp)
                files[rel] = {"bytes": os.path.getsize(p), "sha256": sha256_file(p)}
        manifest = {"kind": self.kind, "meta": self.meta, "files": files}
        mpath = os.path.join(self.tmp, MANIFEST)
        with open(mpath, "w") as fh:
            json.dump(manifest, fh, indent=1, sort_keys=True)
            fh.flush()
            os.fsync(fh.fileno())
        _fsync_dir(self.tmp)
        old = None
        if os.path.exists(self.final):
            old = self.final + f".old-{uuid.uuid4().hex[:8]}"
            os.rename(self.final, old)
        os.rename(self.tmp, self.final)
        _fsync_dir(os.path.dirname(self.final))
        if old:
            shutil.rmtree(old, ignore_errors=True)
        return False


def clean_stale(parent: str) -> list[str]:
    """Remove the temporary folders a writer killed mid-write (``kill -9``, power loss) left in
    ``parent``; returns their names. Call it only where one writer owns the folder (a run's
    checkpoints folder): a live writer's temporary would be removed too."""
    removed = []
    try:
        names = os.listdir(parent)
    except FileNotFoundError:
        return removed
    for n in sorted(names):
        p = os.path.join(parent, n)
        if _STALE.match(n) and os.path.isdir(p) and not os.path.islink(p):
            shutil.rmtree(p, ignore_errors=True)
            removed.append(n)
    return removed


def read_manifest(path: str, kind: str, verify: bool = True) -> dict:
    """Load and check the manifest of a stored directory; verify every file's size and checksum."""
    if not os.path.isdir(path):
        raise CorruptFileError(f"{path}: not found or not a directory (expected a stored {kind})")
    mpath = os.path.join(path, MANIFEST)
    try:
        with open(mpath) as fh:
            manifest = json.load(fh)
    except FileNotFoundError:
        raise CorruptFileError(f"{path}: no {MANIFEST}; this is not a complete stored {kind} "
                               f"(interrupted write or wrong folder)") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise CorruptFileError(f"{mpath}: manifest is not valid JSON ({exc})") from None
    if not isinstance(manifest, dict) or manifest.get("kind") != kind:
        got = manifest.get("kind") if isinstance(manifest, dict) else type(manifest).__name__
        raise CorruptFileError(f"{path}: holds a {got!r}, expected a {kind!r}")
    if verify:
        for rel, info in manifest.get("files", {}).items():
            p = os.path.join(path, rel)
            if not os.path.isfile(p):
                raise CorruptFileError(f"{p}: listed in the manifest but missing")
            size = os.path.getsize(p)
            if size != info["bytes"]:
                raise CorruptFileError(f"{p}: {size} bytes, the manifest says {info['bytes']} "
                                       f"(truncated or altered)")
            if sha256_file(p) != info["sha256"]:
                raise CorruptFileError(f"{p}: checksum mismatch (file altered or corrupt)")
    return manifest
