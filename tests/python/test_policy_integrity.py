"""Integrity of exported policies and training checkpoints: altered weights, an edited
``forward()`` and damaged metadata are refused alike in Python and in the C++ runtime (one corpus
of damaged files goes through both), a policy is checked before ``ernest evaluate`` runs
anything, a writer killed mid-checkpoint leaves nothing behind for good, a corrupt latest
checkpoint points at the newest intact one, and pruning never deletes the checkpoint just saved.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import warnings

import numpy as np
import pytest
import torch

from ernest_cpp import cli, sensing
from ernest_cpp.envs import ErnestEnv
from ernest_cpp.rl import config as C
from ernest_cpp.rl.export import (HASH_KEY, METADATA_FILE, ExportedPolicy, ExportError, _quiet_jit,
                                  export_actor, load_policy, metadata, weights_sha256)
from ernest_cpp.rl.networks import Actor
from ernest_cpp.rl.policy_file import POLICY_KEY
from ernest_cpp.rl.storage import CorruptFileError, clean_stale
from ernest_cpp.rl.checkpoints import load_checkpoint
from ernest_cpp.rl.trainer import Trainer
from test_runtime import run_runtime

LAYOUT = ErnestEnv("flat").observation_layout


def _export(path, seed=0) -> str:
    torch.manual_seed(seed)
    export_actor(Actor(sensing.OBSERVATION_SIZE, sensing.ACTION_SIZE, 64), LAYOUT, str(path))
    return str(path)


def _resave(src: str, dst: str, meta: dict, module=None) -> str:
    """Rewrite a policy file with other metadata (and optionally another module)."""
    with _quiet_jit():
        mod = module if module is not None else torch.jit.load(src)
        torch.jit.save(mod, dst, _extra_files={METADATA_FILE: json.dumps(meta)})
    return dst


def test_weights_digest_is_the_documented_bytes():
    # Independent of the implementation: sha256 over name, shape and float32 bytes, name order.
    import hashlib

    m = torch.nn.Linear(2, 1)
    with torch.no_grad():
        m.weight.copy_(torch.tensor([[0.5, -1.0]]))
        m.bias.fill_(2.0)
    h = hashlib.sha256()
    h.update(b"bias\n1\n" + np.array([2.0], "<f4").tobytes())
    h.update(b"weight\n1,2\n" + np.array([0.5, -1.0], "<f4").tobytes())
    assert weights_sha256(m) == h.hexdigest()


def test_flipped_weight_bytes_are_refused_in_python_and_cpp(tmp_path):
    good = _export(tmp_path / "good.pt")
    mod, meta = load_policy(good)
    assert meta[HASH_KEY] == weights_sha256(mod)
    # Flip 100 bytes inside the first layer's weights, located by their float32 bytes.
    w = next(t for n, t in mod.named_parameters() if n.endswith("weight"))
    data = bytearray(open(good, "rb").read())
    at = data.find(w.detach().numpy().astype("<f4").tobytes()[:64])
    assert at > 0
    for i in range(at + 200, at + 300):
        data[i] ^= 0xFF
    bad = tmp_path / "bad.pt"
    bad.write_bytes(bytes(data))
    # torch itself loads it and computes other actions: the corruption is otherwise silent.
    with _quiet_jit():
        raw = torch.jit.load(str(bad))
    obs = torch.from_numpy(np.full(45, 0.3, np.float32))
    assert not torch.equal(raw(obs), mod(obs))
    with pytest.raises(ExportError, match="do not match the weights_sha256"):
        load_policy(str(bad))
    r = run_runtime("--policy", str(bad), "--scenario", "flat", "--seed", "1", "--duration", "1")
    assert r.returncode == 1 and "checksum mismatch" in r.stderr and "bad.pt" in r.stderr, r.stderr
    r = run_runtime("--policy", good, "--scenario", "flat", "--seed", "1", "--duration", "1")
    assert r.returncode == 0 and "warning" not in r.stderr, r.stderr


def test_policy_without_digest_loads_with_a_warning_and_stamp_adds_it(tmp_path, capsys):
    good = _export(tmp_path / "good.pt")
    _, meta = load_policy(good)
    # as written before any digest existed (dropping one digest alone is an altered file)
    legacy_meta = {k: v for k, v in meta.items() if k not in (HASH_KEY, POLICY_KEY)}
    legacy = _resave(good, str(tmp_path / "legacy.pt"), legacy_meta)
    with pytest.warns(UserWarning, match="stamp-policy"):
        mod, _ = load_policy(legacy)
    r = run_runtime("--policy", legacy, "--scenario", "flat", "--seed", "1", "--duration", "1")
    assert r.returncode == 0 and "no weights_sha256" in r.stderr, r.stderr
    obs = torch.from_numpy(np.random.default_rng(1).normal(size=(8, 45)).astype(np.float32))
    before = mod(obs)
    assert cli.main(["stamp-policy", legacy]) == 0
    assert "weights_sha256" in capsys.readouterr().out
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        stamped, smeta = load_policy(legacy)
    assert smeta[HASH_KEY] == meta[HASH_KEY]  # the same digest the exporter wrote
    assert torch.equal(stamped(obs), before)
    # Stamping never blesses an altered file that already has a digest.
    with _quiet_jit():
        altered = torch.jit.load(good)
    with torch.no_grad():
        next(iter(altered.parameters())).add_(1e-3)
    tampered = _resave(good, str(tmp_path / "tampered.pt"), meta, altered)
    assert cli.main(["stamp-policy", tampered]) == 2
    assert "not re-stamping" in capsys.readouterr().err


class _TwoOut(torch.nn.Module):
    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x[..., :2]


@pytest.mark.parametrize("case", ["module returns 2", "metadata says 10"])
def test_evaluate_refuses_a_wrong_size_policy_before_any_episode(tmp_path, capsys, case):
    with _quiet_jit():
        module = torch.jit.script(_TwoOut())
    meta = metadata(LAYOUT, 2.0)
    if case == "metadata says 10":
        meta["obs_dim"] = 10
    meta[HASH_KEY] = weights_sha256(module)
    path = _resave("", str(tmp_path / "wrong.pt"), meta, module)
    out = tmp_path / "report"
    assert cli.main(["evaluate", "--policy", path, "--out", str(out), "--no-video"]) == 2
    cap = capsys.readouterr()
    assert "[ 1/" not in cap.out  # no episode ran
    assert "wrong.pt" in cap.err and len(cap.err.strip().splitlines()) == 1
    assert ("returns 2 values" if case == "module returns 2" else "maps 10 observation") in cap.err
    assert not (out / "report.md").exists()


def test_writer_killed_mid_checkpoint_leaves_no_temporary_for_good(tmp_path):
    parent = tmp_path / "checkpoints"
    code = ("import sys, time\nfrom ernest_cpp.rl.storage import AtomicDir\n"
            f"with AtomicDir({str(parent / 'step-000000000100')!r}, 'checkpoint') as t:\n"
            "    open(t + '/agent.pt', 'wb').write(b'x' * 1000)\n"
            "    print('writing', flush=True)\n    time.sleep(60)\n")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "writing"
    os.kill(p.pid, signal.SIGKILL)
    p.wait(timeout=30)
    left = os.listdir(parent)
    assert len(left) == 1 and left[0].startswith(".step-000000000100.tmp-")
    os.makedirs(parent / "step-000000000050.old-0123abcd")  # killed while replacing
    os.makedirs(parent / "step-000000000050")
    assert sorted(clean_stale(str(parent))) == sorted([left[0], "step-000000000050.old-0123abcd"])
    assert os.listdir(parent) == ["step-000000000050"]


def _cfg(keep: int) -> dict:
    sets = ["env.id=ernest-toy/PointMass-v0", "td3.hidden=16", "td3.batch_size=32",
            "random_steps=100", "learning_starts=100", "total_steps=200",
            "eval.every_steps=0", "checkpoint.every_steps=100", f"checkpoint.keep={keep}",
            "log.progress_bar=false", "log.tensorboard=false", "buffer_size=1000"]
    return C.build_config("quick", None, sets)


def test_corrupt_latest_checkpoint_points_at_the_good_one_and_pruning_keeps_it(tmp_path):
    run = tmp_path / "run"
    tr = Trainer(_cfg(keep=3), str(run))
    tr.train()
    tr.close()
    ck_root = run / "checkpoints"
    assert sorted(d for d in os.listdir(ck_root) if d.startswith("step-")) == \
        ["step-000000000100", "step-000000000200"]
    stale = ck_root / ".step-000000000300.tmp-deadbeef"  # a save killed with kill -9
    os.makedirs(stale / "buffer")
    agent = ck_root / "step-000000000200" / "agent.pt"
    data = bytearray(agent.read_bytes())
    data[len(data) // 2] ^= 0xFF
    agent.write_bytes(bytes(data))
    with pytest.raises(CorruptFileError) as err:
        load_checkpoint(str(run))
    msg = str(err.value)
    assert "step-000000000200" in msg and "checksum mismatch" in msg
    assert f"newest intact checkpoint is {ck_root / 'step-000000000100'}" in msg
    assert f"echo step-000000000100 > {ck_root / 'LATEST'}" in msg
    # Follow the advice and resume with keep=1: the save at 150 must survive its own pruning.
    (ck_root / "LATEST").write_text("step-000000000100\n")
    tr = Trainer(_cfg(keep=1), str(run), resume=True)
    assert tr.step == 100 and not stale.exists()
    tr.train(total_steps=150)
    tr.close()
    ck = load_checkpoint(str(run), with_buffer=False)
    assert ck["state"]["step"] == 150 and ck["path"].endswith("step-000000000150")
    left = sorted(d for d in os.listdir(ck_root) if d.startswith("step-"))
    # step-100 pruned (older, keep=1); step-200 (beyond the resume point) left to inspect.
    assert left == ["step-000000000150", "step-000000000200"]


def test_export_never_replaces_a_device_pipe_or_folder_and_reports_unwritable_paths(tmp_path,
                                                                                    capsys):
    """The export renames a verified temporary file onto --out: over a pipe or a device node
    (/dev/null, /dev/full, run as root) that would put a regular file in its place, so a target
    that exists and is not a regular file is refused; a path that cannot be written ends with one
    error line (exit 2), not a traceback."""
    import stat

    targets = []
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    targets.append((fifo, stat.S_ISFIFO))
    dev = tmp_path / "full"
    try:
        os.mknod(dev, stat.S_IFCHR | 0o666, os.makedev(1, 7))  # like /dev/full
        targets.append((dev, stat.S_ISCHR))
    except (OSError, AttributeError):
        pass  # no privilege to make device nodes here: the pipe stands for them
    folder = tmp_path / "folder"
    folder.mkdir()
    targets.append((folder, stat.S_ISDIR))
    actor = Actor(sensing.OBSERVATION_SIZE, sensing.ACTION_SIZE, 16)
    for target, kind in targets:
        with pytest.raises(ExportError, match=f"cannot write {target}: not a regular file"):
            export_actor(actor, LAYOUT, str(target))
        assert kind(os.lstat(target).st_mode), target
    assert sorted(os.listdir(tmp_path)) == sorted(t.name for t, _ in targets)  # no temporaries
    # The command: one line, exit code 2, for a refused target and for an unwritable one.
    run = tmp_path / "run"
    tr = Trainer(C.build_config("quick", None, [
        "env.id=ernest-toy/PointMass-v0", "td3.hidden=16", "random_steps=20",
        "learning_starts=20", "total_steps=20", "eval.every_steps=0", "checkpoint.every_steps=20",
        "log.progress_bar=false", "log.tensorboard=false", "buffer_size=100"]), str(run))
    tr.train()
    tr.close()
    capsys.readouterr()
    assert cli.main(["export", str(run), "--out", str(fifo)]) == 2
    assert f"cannot write {fifo}: not a regular file" in capsys.readouterr().err
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    if os.path.isdir("/proc"):  # a folder that takes no new files
        assert cli.main(["export", str(run), "--out", "/proc/ernest-policy.pt"]) == 2
        assert "cannot write /proc/ernest-policy.pt" in capsys.readouterr().err


# ---- the digest of the whole archive, and one corpus of damaged files for both loaders --------
class _Times10(ExportedPolicy):
    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        x = (obs - self.obs_offset) / self.obs_scale
        return 10.0 * (self.act_low + (self.actor(x) + 1.0) * 0.5 * (self.act_high - self.act_low))


class _Constant(ExportedPolicy):
    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return self.act_high + 0.0 * obs[..., :3]


# Metadata damage: (name, edit of the metadata dict or of its JSON text). Each is also written
# with its digest recomputed and with no digest: the metadata checks must refuse it by themselves.
META_DAMAGE = [
    ("policy_rate_hz 0", lambda m: m.update(policy_rate_hz=0.0)),
    ("policy_rate_hz -2", lambda m: m.update(policy_rate_hz=-2.0)),
    ("policy_rate_hz 1e308", lambda m: m.update(policy_rate_hz=1e308)),
    ("policy_rate_hz '2'", lambda m: m.update(policy_rate_hz="2")),
    ("policy_rate_hz NaN literal", '"policy_rate_hz": NaN'),
    ("policy_rate_hz 1e999", '"policy_rate_hz": 1e999'),
    ("no format", lambda m: m.pop("format")),
    ("format v9", lambda m: m.update(format="ernest-policy-v9")),
    ("action_high 100", lambda m: m["action_high"].__setitem__(0, 100.0)),
    ("obs_dim 45.0", lambda m: m.update(obs_dim=45.0)),
    ("obs_dim 44", lambda m: m.update(obs_dim=44)),
    ("act_dim true", lambda m: m.update(act_dim=True)),
    ("obs_scale other table", lambda m: m["obs_scale"].__setitem__(6, 100.0)),
    ("layout v99", lambda m: m.update(layout_version="ernest-obs-v99")),
    ("duplicate member", '"policy_rate_hz": 2.0, "policy_rate_hz": 2.0'),
    ("weights digest not hex", lambda m: m.update(weights_sha256="z" * 64)),
]


def _damaged_text(good_text: str, edit) -> str:
    if isinstance(edit, str):  # replaces the rate member in the text
        assert '"policy_rate_hz": 2.0' in good_text
        return good_text.replace('"policy_rate_hz": 2.0', edit)
    meta = json.loads(good_text)
    edit(meta)
    return json.dumps(meta)


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    """(good file, {case: damaged file})."""
    from ernest_cpp.rl.export import save_stamped
    from ernest_cpp.rl.policy_file import PLACEHOLDER

    d = tmp_path_factory.mktemp("corpus")
    torch.manual_seed(3)
    actor = Actor(sensing.OBSERVATION_SIZE, sensing.ACTION_SIZE, 64)
    good = str(d / "good.pt")
    export_actor(actor, LAYOUT, good)
    extra = {METADATA_FILE: ""}
    with _quiet_jit():
        module = torch.jit.load(good, _extra_files=extra)
    text = extra[METADATA_FILE].decode()
    digest = json.loads(text)[POLICY_KEY]
    files = {}
    for name, cls in (("forward x10", _Times10), ("forward constant", _Constant)):
        with _quiet_jit():
            edited = torch.jit.script(cls(actor, LAYOUT, 2.0))
        files[name] = _resave("", str(d / f"{name}.pt"), json.loads(text), edited)
    # a metadata edit every check accepts: only the digest sees it
    files["observation name edited"] = _write(
        module, text.replace('"lateral_deviation"', '"lateral_deviation_edited"'),
        str(d / "names.pt"))
    for i, (name, edit) in enumerate(META_DAMAGE):
        bad = _damaged_text(text, edit)
        files[f"{name} (stale digest)"] = _write(module, bad, str(d / f"m{i}s.pt"))
        save_stamped(module, bad.replace(digest, PLACEHOLDER), str(d / f"m{i}r.pt"))
        files[f"{name} (re-stamped)"] = str(d / f"m{i}r.pt")
        files[f"{name} (no digest)"] = _write(
            module, bad.replace(f', "{POLICY_KEY}": "{digest}"', ""), str(d / f"m{i}n.pt"))
    return good, files


def _write(module, text: str, path: str) -> str:
    with _quiet_jit():
        torch.jit.save(module, path, _extra_files={METADATA_FILE: text})
    return path


def test_the_archive_digest_is_the_documented_bytes(tmp_path):
    # Independent of the implementation: the records, uncompressed, by name, the id excluded.
    import hashlib
    import zipfile

    path = _export(tmp_path / "p.pt")
    digest = load_policy(path)[1][POLICY_KEY]
    h = hashlib.sha256()
    with zipfile.ZipFile(path) as z:
        records = {i.filename.split("/", 1)[1]: z.read(i) for i in z.infolist()}
    records.pop(".data/serialization_id")
    records["extra/" + METADATA_FILE] = records["extra/" + METADATA_FILE].replace(
        digest.encode(), b"0" * 64)
    for name in sorted(records):
        h.update(f"{name}\n{len(records[name])}\n".encode() + records[name])
    assert h.hexdigest() == digest


def test_python_and_the_runtime_refuse_the_same_damaged_files(corpus):
    from ernest_cpp import evaluate

    good, files = corpus
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        evaluate.controllers(good)
    r = run_runtime("--policy", good, "--scenario", "flat", "--seed", "1", "--duration", "0.5")
    assert r.returncode == 0 and "warning" not in r.stderr, r.stderr
    python_accepts, runtime_accepts = [], []
    for case, path in files.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "no policy_sha256": the no-digest variants
            try:
                evaluate.controllers(path)
                python_accepts.append(case)
            except ValueError as e:
                assert path in str(e), (case, str(e))
        r = run_runtime("--policy", path, "--scenario", "flat", "--seed", "1", "--duration", "0.5")
        if r.returncode == 0:
            runtime_accepts.append(case)
        else:
            assert path in r.stderr, (case, r.stderr)
    assert python_accepts == [] and runtime_accepts == []


def test_an_edited_forward_is_refused_naming_the_digest(corpus):
    _, files = corpus
    for case in ("forward x10", "forward constant"):
        with pytest.raises(ExportError, match="does not match the policy_sha256"):
            load_policy(files[case])
        r = run_runtime("--policy", files[case], "--scenario", "flat", "--seed", "1",
                        "--duration", "0.5")
        assert r.returncode == 1 and "checksum mismatch" in r.stderr, r.stderr
        assert "policy_sha256" in r.stderr


@pytest.mark.parametrize("rate", ["nan", "0", "-2", "inf"])
def test_export_refuses_a_rate_that_is_not_finite_and_positive(rate, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["export", str(tmp_path), "--out", str(tmp_path / "p.pt"), "--policy-rate", rate])
    assert e.value.code == 2 and "--policy-rate" in capsys.readouterr().err
    with pytest.raises(ExportError, match="policy_rate_hz"):
        export_actor(Actor(45, 3, 8), LAYOUT, str(tmp_path / "p.pt"), float(rate))
    assert not (tmp_path / "p.pt").exists()
