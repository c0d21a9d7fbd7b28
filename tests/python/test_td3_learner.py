"""The TD3 learner (fused Adam, one foreach soft update) against the plain definition: Adam's
per-tensor loop and a per-tensor Polyak loop. Same seed -> same initial weights and the same gradient
steps; checkpoints (also those saved with the per-tensor Adam) load and continue; an incompatible
critic layout is a clear error; ``learner_device`` is resolved and validated."""

from __future__ import annotations

import copy

import pytest
import torch
import torch.nn.functional as F

torch.set_num_threads(1)

from ernest_cpp.rl import config as C  # noqa: E402
from ernest_cpp.rl.networks import Actor, TwinCritic  # noqa: E402
from ernest_cpp.rl.td3 import TD3, TD3Config, resolve_device  # noqa: E402

OBS, ACT = 7, 3


class ReferenceTD3:
    """TD3 written out plainly: Adam's per-tensor loop, a per-tensor Polyak loop."""

    def __init__(self, cfg: TD3Config, seed: int):
        self.c = cfg
        self.gen = torch.Generator().manual_seed(seed)
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)
            self.actor = Actor(OBS, ACT, cfg.hidden)
            self.critic = TwinCritic(OBS, ACT, cfg.hidden)
        self.actor_target = copy.deepcopy(self.actor).requires_grad_(False)
        self.critic_target = copy.deepcopy(self.critic).requires_grad_(False)
        self.actor_opt = torch.optim.Adam(self.actor.parameters(), lr=cfg.actor_lr)
        self.critic_opt = torch.optim.Adam(self.critic.parameters(), lr=cfg.critic_lr)
        self.updates = 0
        self.anchor = None  # (frozen actor, weight): TD3+BC's term towards a policy

    def update(self, b: dict) -> dict:
        c = self.c
        with torch.no_grad():
            eps = (torch.randn(b["act"].shape, generator=self.gen) * c.target_noise)
            eps = eps.clamp(-c.target_noise_clip, c.target_noise_clip)
            na = (self.actor_target(b["next_obs"]) + eps).clamp(-1.0, 1.0)
            t1, t2 = self.critic_target(b["next_obs"], na)
            y = b["rew"] + c.gamma * (1.0 - b["done"]) * torch.min(t1, t2)
        q1, q2 = self.critic(b["obs"], b["act"])
        loss = F.mse_loss(q1, y) + F.mse_loss(q2, y)
        self.critic_opt.zero_grad()
        loss.backward()
        self.critic_opt.step()
        self.updates += 1
        info = {"critic_loss": loss.item(), "q1": q1.mean().item(), "q_target": y.mean().item()}
        if self.updates % c.policy_delay == 0:
            pi = self.actor(b["obs"])
            q = self.critic.q1(b["obs"], pi)
            actor_loss = -q.mean()
            if self.anchor is not None:
                ref, w = self.anchor
                dev = ((pi - ref(b["obs"]).detach()) ** 2).sum(dim=1).mean()
                actor_loss = actor_loss + w * q.detach().abs().mean() * dev
            self.actor_opt.zero_grad()
            actor_loss.backward()
            self.actor_opt.step()
            with torch.no_grad():
                for net, tgt in ((self.actor, self.actor_target), (self.critic, self.critic_target)):
                    for p, tp in zip(net.parameters(), tgt.parameters()):
                        tp.mul_(1.0 - c.tau).add_(p, alpha=c.tau)
            info["actor_loss"] = actor_loss.item()
        return info

    def state_dict(self) -> dict:  # TD3.state_dict's layout
        return {"actor": self.actor.state_dict(), "critic": self.critic.state_dict(),
                "actor_target": self.actor_target.state_dict(),
                "critic_target": self.critic_target.state_dict(),
                "actor_opt": self.actor_opt.state_dict(), "critic_opt": self.critic_opt.state_dict(),
                "gen": self.gen.get_state(), "updates": torch.tensor(self.updates),
                "dims": torch.tensor([OBS, ACT, self.c.hidden])}


def _batches(n: int, size: int = 16, seed: int = 0) -> list[dict]:
    g = torch.Generator().manual_seed(seed)
    return [{"obs": torch.randn(size, OBS, generator=g),
             "act": torch.rand(size, ACT, generator=g) * 2 - 1,
             "rew": torch.randn(size, generator=g),
             "next_obs": torch.randn(size, OBS, generator=g),
             "done": (torch.rand(size, generator=g) < 0.2).float()} for _ in range(n)]


def _cfg(**kw) -> TD3Config:
    base = {"hidden": 32, "batch_size": 16, "actor_lr": 1e-3, "critic_lr": 1e-3}
    return TD3Config(**{**base, **kw}).validate()


def _assert_same_networks(agent: TD3, ref: ReferenceTD3, **tol):
    for net in ("actor", "actor_target", "critic", "critic_target"):
        mine, theirs = getattr(agent, net).state_dict(), getattr(ref, net).state_dict()
        assert mine.keys() == theirs.keys()
        for k, v in mine.items():
            torch.testing.assert_close(v, theirs[k], **tol)


# ------------------------------------------------------------------------------ the update
@pytest.mark.parametrize("policy_delay", [1, 2])
def test_updates_follow_the_plain_definition(policy_delay):
    """Same seed: same initial weights; 12 updates of ours and of the plain TD3 end at the same
    weights (to float rounding: fused Adam and lerp order their arithmetic differently), with the
    same info."""
    cfg = _cfg(policy_delay=policy_delay)
    agent, ref = TD3(OBS, ACT, cfg, seed=4), ReferenceTD3(cfg, seed=4)
    _assert_same_networks(agent, ref, rtol=0, atol=0)
    for b in _batches(12):
        info, info_ref = agent.update(b), ref.update(b)
        assert info.keys() == info_ref.keys()
        for k in info:
            assert info[k] == pytest.approx(info_ref[k], rel=1e-4, abs=1e-6), k
    assert agent.updates == ref.updates == 12
    _assert_same_networks(agent, ref, rtol=1e-4, atol=1e-6)


def test_the_anchor_term_follows_its_definition_and_holds_the_actor():
    """With an anchor the actor loss is -Q1 + w·mean|Q1|·mean‖π - π_anchor‖² (plain reference to
    float rounding); a heavy anchor keeps the actor nearer its starting policy than none does."""
    cfg = _cfg(policy_delay=1)
    agent, ref = TD3(OBS, ACT, cfg, seed=4), ReferenceTD3(cfg, seed=4)
    start = copy.deepcopy(agent.actor)
    agent.set_anchor(start, 0.5)
    ref.anchor = (copy.deepcopy(start).requires_grad_(False), 0.5)
    for b in _batches(12):
        info, info_ref = agent.update(b), ref.update(b)
        assert info["actor_loss"] == pytest.approx(info_ref["actor_loss"], rel=1e-4, abs=1e-6)
    _assert_same_networks(agent, ref, rtol=1e-4, atol=1e-6)

    probe = torch.randn(256, OBS, generator=torch.Generator().manual_seed(1))
    drift = {}
    for w in (0.0, 50.0):
        a = TD3(OBS, ACT, _cfg(policy_delay=1, actor_lr=1e-2), seed=4)
        a.set_anchor(copy.deepcopy(a.actor), w)
        assert (a.anchor is None) == (w == 0.0)
        for b in _batches(60, seed=3):
            a.update(b)
        with torch.no_grad():
            drift[w] = (a.actor(probe) - start(probe)).pow(2).sum(1).mean().item()
    assert drift[50.0] < 0.25 * drift[0.0], drift
    # a batch's anchor_mask picks the rows held: none held is the plain update, all held the
    # unmasked one
    runs = {}
    for name, w, mask in (("plain", 0.0, None), ("none held", 0.5, 0.0), ("all held", 0.5, 1.0),
                          ("unmasked", 0.5, None)):
        a = TD3(OBS, ACT, cfg, seed=4)
        a.set_anchor(copy.deepcopy(a.actor), w)
        for b in _batches(6, seed=5):
            if mask is not None:
                b = {**b, "anchor_mask": torch.full((b["obs"].shape[0],), mask)}
            a.update(b)
        runs[name] = a.actor.state_dict()
    for x, y in (("plain", "none held"), ("unmasked", "all held")):
        for k, v in runs[x].items():
            torch.testing.assert_close(runs[y][k], v, rtol=0, atol=0)
    assert any(not torch.equal(runs["plain"][k], v) for k, v in runs["unmasked"].items())
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="anchor weight"):
            agent.set_anchor(start, bad)


def test_info_keys_and_same_seed_same_result():
    cfg = _cfg()
    a, b = TD3(OBS, ACT, cfg, seed=9), TD3(OBS, ACT, cfg, seed=9)
    batches = _batches(5)
    infos = [a.update(x) for x in batches]
    assert [set(i) for i in infos[:2]] == [{"critic_loss", "q1", "q_target"},
                                          {"critic_loss", "q1", "q_target", "actor_loss"}]
    assert [b.update(x) for x in batches] == infos
    for k, v in a.state_dict().items():
        if isinstance(v, dict) and k.endswith("_opt"):
            continue
        for kk, vv in (v.items() if isinstance(v, dict) else [(k, v)]):
            assert torch.equal(vv, (b.state_dict()[k][kk] if isinstance(v, dict)
                                    else b.state_dict()[k])), (k, kk)


def test_checkpoint_round_trip_continues_identically():
    cfg = _cfg()
    a = TD3(OBS, ACT, cfg, seed=2)
    batches = _batches(8)
    for x in batches[:3]:
        a.update(x)
    b = TD3(OBS, ACT, cfg, seed=77)
    b.load_state_dict(copy.deepcopy(a.state_dict()))
    for x in batches[3:]:
        assert a.update(x) == b.update(x)
    for net in ("actor", "critic", "actor_target", "critic_target"):
        for k, v in getattr(a, net).state_dict().items():
            assert torch.equal(v, getattr(b, net).state_dict()[k]), (net, k)


def test_checkpoint_of_the_per_tensor_adam_loads_and_continues():
    """A checkpoint whose Adam ran the per-tensor loop loads; the fused kernel stays."""
    cfg = _cfg()
    ref = ReferenceTD3(cfg, seed=3)
    batches = _batches(10)
    for x in batches[:5]:  # 5 updates: an odd count, the next actor step is due at update 6
        ref.update(x)
    agent = TD3(OBS, ACT, cfg, seed=0)
    agent.load_state_dict(copy.deepcopy(ref.state_dict()))
    assert agent.updates == 5
    _assert_same_networks(agent, ref, rtol=0, atol=0)
    assert ref.critic_opt.param_groups[0]["fused"] is None
    for opt in (agent.actor_opt, agent.critic_opt):  # the saved per-tensor loop is not taken over
        assert opt.param_groups[0]["fused"]
    for x in batches[5:]:
        info, info_ref = agent.update(x), ref.update(x)
        assert info.keys() == info_ref.keys()
    _assert_same_networks(agent, ref, rtol=1e-4, atol=1e-6)


def test_incompatible_critic_layout_is_a_clear_error():
    cfg = _cfg()
    sd = TD3(OBS, ACT, cfg, seed=0).state_dict()
    bad = copy.deepcopy(sd)
    bad["critic"] = {"l1.weight": torch.zeros(1)}  # one critic, not two
    with pytest.raises(ValueError, match="checkpoint critic: incompatible critic layout"):
        TD3(OBS, ACT, cfg, seed=0).load_state_dict(bad)
    stacked = copy.deepcopy(sd)  # both critics' weights stacked in one tensor per layer
    stacked["critic_target"] = {n: torch.zeros(2, 1) for n in ("w1", "b1", "w2", "b2", "w3", "b3")}
    with pytest.raises(ValueError, match="checkpoint critic_target: incompatible critic layout"):
        TD3(OBS, ACT, cfg, seed=0).load_state_dict(stacked)
    with pytest.raises(ValueError, match="hidden"):
        TD3(OBS, ACT, _cfg(hidden=16), seed=0).load_state_dict(sd)


# ------------------------------------------------------------------------------ learner device
def test_learner_device_resolves_and_validates(monkeypatch):
    assert resolve_device("cpu") == "cpu"
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: 0)
    assert resolve_device("auto") == "cpu"
    with pytest.raises(ValueError, match="learner_device .*no GPU"):
        resolve_device("cuda")
    for bad in ("gpu", "cuda:x", "", 1, None, "CPU"):
        with pytest.raises(ValueError, match="learner_device = .*auto, cpu, cuda or cuda:N"):
            resolve_device(bad)
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: 2)
    assert resolve_device("auto") == "cuda"
    assert resolve_device("cuda:1") == "cuda:1"
    with pytest.raises(ValueError, match="cuda:2.*2 GPU"):
        resolve_device("cuda:2")


def test_presets_learn_where_a_gpu_is_and_train_on_one_thread():
    for name in C.PRESETS:
        cfg = C.load_preset(name)
        assert cfg["learner_device"] == "auto"
        assert cfg["torch_threads"] == 1


def test_trainer_rejects_a_bad_learner_device(tmp_path):
    from ernest_cpp.rl.trainer import Trainer

    cfg = C.build_config("quick", None, ["env.id=ernest-toy/PointMass-v0", "learner_device=tpu",
                                         "log.progress_bar=false", "log.tensorboard=false"])
    with pytest.raises(ValueError, match="learner_device = 'tpu'"):
        Trainer(cfg, str(tmp_path / "run"))
    cfg = C.build_config("quick", None, ["env.id=ernest-toy/PointMass-v0", "learner_device=cpu",
                                         "log.progress_bar=false", "log.tensorboard=false",
                                         "td3.hidden=16"])
    tr = Trainer(cfg, str(tmp_path / "run2"))
    assert tr.agent.device == torch.device("cpu")
    tr.close()
