"""Value-based training (CrowdNav's CADRL and SARL): imitation of the ORCA robot, then TD learning with an
ε-greedy one-step look-ahead — CrowdNav's ``train.py`` / ``utils/{explorer,trainer,memory}.py`` at 20d6780, batched.

The networks and the look-ahead live in :mod:`crowdbench.policies.value`; this module holds the run:

1. **Imitation** (``il``): ``il_episodes`` episodes of the ORCA robot (safety space 0.15 m); the states of successful
   and collided episodes go to the replay memory with their discounted returns (CrowdNav's reward, discount
   γ^{Δt·v_pref}); ``il_epochs`` epochs of SGD (momentum 0.9, lr 0.01, batches of 100) over the memory.
2. **RL** (``rl``): ``rl_episodes`` episodes of the greedy look-ahead with ε linear from 0.5 to 0.1 over the first
   4,000; TD targets ``r + γ̄·V_target(s′)`` computed once, at insertion, with the target network (copied every 50
   episodes); only success/collision episodes stored; 100 batches of 100 per episode at lr 1e-3.

**Batched**: ``worlds`` episodes run at once (CrowdNav's ``sample_episodes``), one network pass per step over all
worlds × 81 actions × sensed pedestrians, then ``worlds × 100`` SGD batches — the same episode and update counts as
the original. Episode ``k`` of phase ``p`` runs world seed ``SeedSequence([seed, p, k])``; each round draws the crowd's
mean responsiveness ρ ~ U(``rho_range``) from the run's generator, which also drives exploration and batch sampling, so
a run is reproducible and a resumed run continues exactly (checkpoints at round boundaries hold the memory, both
networks, the optimiser and the generator).
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import json
import os
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from crowdbench.policies import POLICIES, trained_by
from crowdbench.policies.value import DEFAULT_VALUE_METHOD


def value_methods() -> list[str]:
    """The registered methods this module trains (``trainer="value"``)."""
    return trained_by("value")


def discounted_returns(rewards: np.ndarray, gamma: np.ndarray | float) -> np.ndarray:
    """Return-to-go of one episode: ``G_t = r_t + γ_t G_{t+1}`` for rewards ``(T,)`` and per-step discount
    ``gamma`` (scalar or ``(T,)``; CrowdNav discounts by γ^{Δt·v_pref}). Shape ``(T,)``."""
    rewards = np.asarray(rewards, dtype=np.float64)
    g = np.broadcast_to(np.asarray(gamma, dtype=np.float64), rewards.shape)
    out = np.empty_like(rewards)
    acc = 0.0
    for t in range(len(rewards) - 1, -1, -1):
        acc = rewards[t] + g[t] * acc
        out[t] = acc
    return out


class ReplayMemory:
    """Fixed-capacity ring buffer of (state, target) pairs, as CrowdNav's ``ReplayMemory``: once full, new items
    overwrite the oldest.

    Args:
        capacity: Items kept (CrowdNav: 100,000).
        shapes: Per-item shape of each stored field, e.g. ``{"state": (N, 13), "value": ()}``.
    """

    def __init__(self, capacity: int, shapes: dict[str, tuple[int, ...]]) -> None:
        if not isinstance(capacity, int) or capacity < 1:
            raise ValueError(f"capacity={capacity!r}; valid choices: an integer ≥ 1")
        self.capacity = capacity
        self.data = {k: np.zeros((capacity, *s), np.float32) for k, s in shapes.items()}
        self.size = 0
        self.head = 0

    def __len__(self) -> int:
        return self.size

    def push(self, **items: np.ndarray) -> None:
        """Append a batch: every field ``(k, *shape)``, the same ``k``; the oldest items are overwritten."""
        if set(items) != set(self.data):
            raise ValueError(f"push: fields {sorted(items)}; valid choices: exactly {sorted(self.data)}")
        k = len(next(iter(items.values())))
        idx = (self.head + np.arange(k)) % self.capacity
        for name, value in items.items():
            self.data[name][idx] = value
        self.head = int((self.head + k) % self.capacity)
        self.size = min(self.size + k, self.capacity)

    def sample(self, batch: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
        """``batch`` items drawn uniformly with replacement (``rng``: the caller's generator)."""
        if self.size == 0:
            raise ValueError("sample: the memory is empty")
        idx = rng.integers(0, self.size, batch)
        return {k: v[idx] for k, v in self.data.items()}


    def state_dict(self) -> dict[str, Any]:
        import torch

        return {"data": {k: torch.from_numpy(v[:self.size].copy()) for k, v in self.data.items()},
                "size": self.size, "head": self.head}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.size, self.head = int(d["size"]), int(d["head"])
        for k, v in d["data"].items():
            self.data[k][:self.size] = v.numpy()


IL_CHECKPOINT_EVERY = 10
"""Imitation epochs between checkpoints: each holds the whole replay memory (169 MB at CrowdNav's 100,000 items;
SARL: ≈ 1.6 s to write against ≈ 9.5 s of SGD per epoch), so one after every epoch costs a sixth of the phase."""

CLOCK = ("episodes", "targets", "sgd", "evaluation", "checkpoints")
"""Where a run's wall-clock time goes (seconds per activity, kept in ``history.json``)."""
PHASES = ("il", "il_fit", "rl", "done")
RESUMABLE = ("minutes", "threads")
"""Fields a resumed run may change."""


@dataclass(frozen=True)
class ValueTrainConfig:
    """A CADRL or SARL training run (defaults: CrowdNav's ``train.config``). Unknown keys are an error."""

    method: str = DEFAULT_VALUE_METHOD
    """A registered method with ``trainer="value"`` (:func:`value_methods`: CADRL or SARL)."""
    model: dict[str, Any] = dataclasses.field(default_factory=dict)
    """Architecture overrides (fields of :class:`~crowdbench.policies.value.model.CADRLConfig` / ``SARLConfig``)."""
    seed: int = 0
    """Seeds the network initialisation, the episode seeds and the run's generator."""
    worlds: int = 10
    """Episodes run at once (CrowdNav's ``sample_episodes``)."""
    il_episodes: int = 3000
    """Demonstration episodes of the ORCA robot."""
    il_epochs: int = 50
    """Imitation epochs over the replay memory."""
    il_learning_rate: float = 0.01
    """SGD learning rate of imitation."""
    rl_episodes: int = 10000
    """TD-learning episodes."""
    rl_learning_rate: float = 0.001
    """SGD learning rate of TD learning."""
    momentum: float = 0.9
    """SGD momentum (both phases)."""
    batch_size: int = 100
    """Samples per SGD batch."""
    batches_per_episode: int = 100
    """SGD batches per RL episode (``train_batches``)."""
    gamma: float = 0.9
    """Discount per second at v_pref = 1 m/s (applied as γ^{Δt·v_pref} per step)."""
    epsilon_start: float = 0.5
    """Exploration rate of the first RL episode."""
    epsilon_end: float = 0.1
    """Exploration rate after ``epsilon_decay`` episodes."""
    epsilon_decay: int = 4000
    """Episodes of the linear ε schedule."""
    target_update: int = 50
    """Episodes between copies of the network into the target network."""
    capacity: int = 100000
    """Replay-memory size (shared by both phases, as CrowdNav)."""
    humans_range: tuple[int, int] = (10, 30)
    """Pedestrians per training episode, drawn uniformly (H²INT's training crowds)."""
    rho_range: tuple[float, float] = (0.0, 0.8)
    """Each round's crowd mean responsiveness ρ ~ U(lo, hi): the range H²INT's curriculum covers (the value
    methods have no curriculum)."""
    checkpoint_every: int = 500
    """Episodes (RL) between checkpoints; imitation checkpoints after collecting, after every
    :data:`IL_CHECKPOINT_EVERY` epochs and at the switch to RL."""
    eval_every: int = 1000
    """RL episodes between quick greedy evaluations (circle crossing, N = 20, ρ = 0.5; CrowdNav validates every
    1,000); 0 = none."""
    eval_episodes: int = 100
    """Episodes per quick evaluation."""
    minutes: float = 0.0
    """The run's total wall-clock budget in minutes, a resumed run counting its earlier minutes (0 = none). The
    run stops at the first round boundary past it."""
    threads: int = 1
    """torch threads."""
    sensing: Literal["positions", "velocities", "full"] = "positions"
    """Sensing tier the value network trains and acts at (``positions``: velocities estimated from positions;
    ``velocities``: true velocities and radii), the ORCA demonstrator's included."""
    free_space: bool = False
    """Value states with nobody sensed analytically, in the look-ahead and in the TD targets
    (:func:`~crowdbench.policies.value.lookahead.free_space_value`). Off: a CADRL run with it (seed 0, 10,000 TD
    episodes) scored 53.8 % at N = 20, ρ = 0.5 against 69.2 % without (500 episodes each; README, "Baselines CADRL and
    SARL") — its timeouts are the robot hovering at the crowd's edge while it senses someone, not runs into empty
    space."""

    def __post_init__(self) -> None:
        from crowdbench.policies.value.model import build_net

        if not isinstance(self.free_space, bool):
            raise ValueError(f"free_space={self.free_space!r}; valid choices: true, false")
        from crowdbench.robots.observations import check_sensing

        check_sensing(self.sensing)

        if self.method not in value_methods():
            raise ValueError(f"method={self.method!r}; valid choices: {', '.join(value_methods())}")
        build_net(self.method, self.model)  # unknown architecture keys: one clear error
        object.__setattr__(self, "model", {k: list(v) for k, v in self.model.items()})
        object.__setattr__(self, "humans_range", tuple(int(n) for n in self.humans_range))
        object.__setattr__(self, "rho_range", tuple(float(r) for r in self.rho_range))
        for name in ("worlds", "il_epochs", "batch_size", "epsilon_decay", "target_update", "capacity",
                     "checkpoint_every", "eval_episodes", "threads"):
            if not isinstance(getattr(self, name), int) or getattr(self, name) < 1:
                raise ValueError(f"{name}={getattr(self, name)!r}; valid choices: an integer ≥ 1")
        for name in ("il_episodes", "rl_episodes", "batches_per_episode", "eval_every"):
            if not isinstance(getattr(self, name), int) or getattr(self, name) < 0:
                raise ValueError(f"{name}={getattr(self, name)!r}; valid choices: an integer ≥ 0")
        for name in ("gamma", "momentum", "epsilon_start", "epsilon_end"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{name}={getattr(self, name)}; valid choices: a number in [0, 1]")
        for name in ("il_learning_rate", "rl_learning_rate"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name}={getattr(self, name)}; valid choices: a positive number")
        lo, hi = self.humans_range
        if not 0 <= lo <= hi:
            raise ValueError(f"humans_range={self.humans_range}; valid choices: (low, high) with 0 ≤ low ≤ high")
        lo, hi = self.rho_range
        if not 0.0 <= lo <= hi <= 1.0:
            raise ValueError(f"rho_range={self.rho_range}; valid choices: (low, high) with 0 ≤ low ≤ high ≤ 1")
        if self.minutes < 0:
            raise ValueError(f"minutes={self.minutes}; valid choices: ≥ 0 (0 = no wall-clock budget)")

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["humans_range"], d["rho_range"] = list(self.humans_range), list(self.rho_range)
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ValueTrainConfig:
        from crowdbench.training.config import _strict

        return _strict(cls, d, "value train config")

    def epsilon(self, episode: int) -> float:
        """CrowdNav's linear exploration schedule at RL episode ``episode``."""
        if episode >= self.epsilon_decay:
            return self.epsilon_end
        return self.epsilon_start + (self.epsilon_end - self.epsilon_start) / self.epsilon_decay * episode


@dataclass
class Rollout:
    """One finished episode: joint states ``(T, K, 13)``, masks ``(T, K)``, CrowdNav rewards ``(T,)``, outcome, and
    which states had nobody sensed ``(T,)`` (their slot 0 holds the dummy)."""

    states: np.ndarray
    masks: np.ndarray
    rewards: np.ndarray
    outcome: str
    free: np.ndarray


class ValueTrainer:
    """One CADRL/SARL run in ``out``: ``last.pt`` (full state, resumable), ``policy.pt`` (the network and its
    metadata: what is shipped), ``history.json``, ``curve.png``."""

    def __init__(self, cfg: ValueTrainConfig, out: str, quiet: bool = False) -> None:
        import torch

        from crowdbench.config import make_config
        from crowdbench.policies.classic import ORCAPolicy
        from crowdbench.policies.value.model import build_net
        from crowdbench.robots.observations import make_observation
        from crowdbench.worlds.world import CrowdWorld

        torch.set_num_threads(cfg.threads)
        self.cfg, self.out, self.quiet = cfg, out, quiet
        os.makedirs(out, exist_ok=True)
        torch.manual_seed(cfg.seed)
        self.net = build_net(cfg.method, cfg.model)
        self.target = copy.deepcopy(self.net)
        self.config = make_config(humans_range=cfg.humans_range)
        self.policy = POLICIES.get(cfg.method)(self.config, net=self.net, gamma=cfg.gamma, free_space=cfg.free_space,
                                 sensing=cfg.sensing)
        # CrowdNav's il_policy: ORCA, safety space 0.15 m, sensing what the learner senses
        self.demonstrator = ORCAPolicy(self.config, sensing=cfg.sensing)
        self.world = CrowdWorld(self.config, cfg.worlds, "circle_crossing", "responsive_orca")
        self.obs = make_observation(self.policy.observation, self.config)
        n = self.config.max_humans_observed
        self.memory = ReplayMemory(cfg.capacity, {"state": (n, 13), "mask": (n,), "value": ()})
        self.rng = np.random.default_rng(cfg.seed)
        self.optimizer = self._sgd(cfg.il_learning_rate)
        self.phase, self.episode, self.epoch = "il", 0, 0
        self.elapsed = 0.0
        self.clock = dict.fromkeys(CLOCK, 0.0)
        self.history: dict[str, list] = {k: [] for k in ("phase", "episode", "time", "success", "collision",
                                                         "timeout", "epsilon", "loss", "memory")}
        self.evals: list[dict[str, Any]] = []
        self.gamma_step = cfg.gamma ** (self.config.time_step * self.config.robot_v_pref)

    @contextlib.contextmanager
    def _timed(self, activity: str) -> Iterator[None]:
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.clock[activity] += time.perf_counter() - t0

    def _sgd(self, lr: float):
        import torch

        return torch.optim.SGD(self.net.parameters(), lr=lr, momentum=self.cfg.momentum)

    # ------------------------------------------------------------------ episodes
    def episode_seed(self, phase: str, k: int) -> int:
        return int(np.random.SeedSequence([self.cfg.seed, PHASES.index(phase), k]).generate_state(1)[0])

    def run_round(self, n: int, phase: str, epsilon: float = 0.0) -> list[Rollout]:
        """Run episodes ``self.episode … + n`` of ``phase`` at once (ORCA demonstrator in ``il``, the ε-greedy
        look-ahead in ``rl``); returns them in episode order."""
        from crowdbench.policies.value.lookahead import CROWDNAV_REWARD, Scene, current_state
        from crowdbench.worlds.world import COLLISION, OUTCOMES, SUCCESS

        world, cfg = self.world, self.cfg
        world.human_model.set_responsiveness(float(self.rng.uniform(*cfg.rho_range)))
        live = np.zeros(cfg.worlds, dtype=bool)
        live[:n] = True
        world.reset(seeds=[self.episode_seed(phase, self.episode + i) for i in range(n)], mask=live)
        buf: list[list[tuple]] = [[] for _ in range(n)]
        outcome = [""] * n
        while live.any():
            full = self.obs.build(world)
            obs = {k: v[live] for k, v in full.items()}
            action = np.zeros((cfg.worlds, 2))
            if phase == "il":
                action[live] = self.demonstrator.act(obs)
                scene = Scene.from_obs(obs, self.policy.sensing_range)
            else:
                action[live], scene = self.policy.plan(obs, epsilon, self.rng)
            states, masks = current_state(scene).numpy(), scene.mask.numpy()
            free = ~scene.sensed.any(dim=1).numpy()
            res = world.step(action)
            r = CROWDNAV_REWARD.of_step(res.outcome == SUCCESS, res.outcome == COLLISION, res.d_min, world.dt)
            for j, b in enumerate(np.flatnonzero(live)):
                buf[b].append((states[j], masks[j], r[b], free[j]))
                if res.terminated[b] or res.truncated[b]:
                    outcome[b] = OUTCOMES[int(res.outcome[b])]
                    live[b] = False
        n_max = self.config.max_humans_observed
        out = []
        for b in range(n):
            T = len(buf[b])
            states = np.zeros((T, n_max, 13), np.float32)
            masks = np.zeros((T, n_max), np.float32)
            for t, (s, m, _, _) in enumerate(buf[b]):
                states[t, :s.shape[0]], masks[t, :m.shape[0]] = s, m
            out.append(Rollout(states, masks, np.array([x[2] for x in buf[b]]), outcome[b],
                               np.array([x[3] for x in buf[b]], dtype=bool)))
        return out

    def targets(self, ep: Rollout, imitation: bool) -> np.ndarray:
        """Value targets ``(T,)``: discounted returns (imitation) or one-step TD targets with the target network
        (next states with nobody sensed valued by ``free_space_value`` when the run uses it)."""
        import torch

        from crowdbench.policies.value.lookahead import free_space_value

        if imitation:
            return discounted_returns(ep.rewards, self.gamma_step)
        values = ep.rewards.astype(np.float64).copy()
        if len(values) > 1:
            states = torch.from_numpy(ep.states[1:])
            with torch.inference_mode():
                nxt = self.target(states, torch.from_numpy(ep.masks[1:] > 0.5))
                if self.cfg.free_space and ep.free[1:].any():
                    free = torch.from_numpy(ep.free[1:])
                    robot = states[free, 0]  # [d_g, v_pref, ...] of the joint state
                    nxt[free] = free_space_value(robot[:, 0], robot[:, 1], self.config.time_step, self.cfg.gamma,
                                                 self.config.reward.goal_tolerance)
            values[:-1] += self.gamma_step * nxt.numpy()
        return values

    def store(self, episodes: list[Rollout], imitation: bool) -> None:
        """Push the states of successful and collided episodes (CrowdNav skips timeouts)."""
        for ep in episodes:
            if ep.outcome in ("success", "collision"):
                self.memory.push(state=ep.states, mask=ep.masks, value=self.targets(ep, imitation))

    # ------------------------------------------------------------------ SGD
    def sgd_step(self, batch: dict[str, np.ndarray]) -> float:
        import torch

        k = max(int(batch["mask"].sum(axis=1).max()), 1)
        state = torch.from_numpy(batch["state"][:, :k])
        mask = torch.from_numpy(batch["mask"][:, :k] > 0.5)
        loss = torch.nn.functional.mse_loss(self.net(state, mask), torch.from_numpy(batch["value"]))
        self.optimizer.zero_grad(set_to_none=True)
        loss.backward()
        self.optimizer.step()
        return loss.item()

    def fit_epoch(self) -> float:
        """One imitation epoch: every memory item once, shuffled, in batches of ``batch_size``."""
        order = self.rng.permutation(len(self.memory))
        losses = [self.sgd_step({k: v[idx] for k, v in self.memory.data.items()})
                  for idx in np.array_split(order, max(1, -(-len(order) // self.cfg.batch_size)))]
        return float(np.mean(losses))

    def fit_batches(self, batches: int) -> float:
        if len(self.memory) == 0 or batches == 0:
            return float("nan")
        return float(np.mean([self.sgd_step(self.memory.sample(self.cfg.batch_size, self.rng))
                              for _ in range(batches)]))

    # ------------------------------------------------------------------ loop
    def train(self, rounds: int | None = None) -> None:
        """Run (or continue) the phases until done, out of the wall-clock budget, or — if given — after ``rounds``
        rounds (episode rounds or imitation epochs; a checkpoint is written there, as on a budget stop)."""
        cfg = self.cfg
        t_start, start_elapsed = time.time(), self.elapsed
        last_save = self.episode
        done_rounds = 0

        def out_of_time() -> bool:
            self.elapsed = start_elapsed + time.time() - t_start
            return bool(cfg.minutes and self.elapsed >= cfg.minutes * 60)

        while self.phase != "done":
            if self.phase == "il":
                n = min(max(cfg.worlds, 1), cfg.il_episodes - self.episode)
                if n > 0:
                    with self._timed("episodes"):
                        eps = self.run_round(n, "il")
                    with self._timed("targets"):
                        self.store(eps, imitation=True)
                    self.episode += n
                    self._record(eps, 0.0, float("nan"))
                if self.episode >= cfg.il_episodes:
                    self.phase, self.epoch = "il_fit", 0
                    self.save()
            elif self.phase == "il_fit":
                if self.epoch < cfg.il_epochs and len(self.memory):
                    with self._timed("sgd"):
                        loss = self.fit_epoch()
                    self.epoch += 1
                    self._record([], 0.0, loss)
                    if self.epoch % IL_CHECKPOINT_EVERY == 0:
                        self.save(figure=False)
                else:
                    self.phase, self.episode = "rl", 0
                    self.optimizer = self._sgd(cfg.rl_learning_rate)
                    self.target.load_state_dict(self.net.state_dict())
                    self._evaluate()
                    self.save()
            else:  # rl
                if self.episode >= cfg.rl_episodes:
                    self.phase = "done"
                    self._evaluate()
                    self.save()
                    break
                n = min(cfg.worlds, cfg.rl_episodes - self.episode)
                eps_rate = cfg.epsilon(self.episode)
                with self._timed("episodes"):
                    eps = self.run_round(n, "rl", eps_rate)
                with self._timed("targets"):
                    self.store(eps, imitation=False)
                with self._timed("sgd"):
                    loss = self.fit_batches(n * cfg.batches_per_episode)
                before, self.episode = self.episode, self.episode + n
                if self.episode // cfg.target_update > before // cfg.target_update:
                    self.target.load_state_dict(self.net.state_dict())
                self._record(eps, eps_rate, loss)
                if cfg.eval_every and self.episode // cfg.eval_every > before // cfg.eval_every:
                    self._evaluate()
                if self.episode - last_save >= cfg.checkpoint_every:
                    self.save()
                    last_save = self.episode
            self._progress()
            done_rounds += 1
            if out_of_time() or (rounds is not None and done_rounds >= rounds):
                self.save()
                break
        if not self.quiet:
            print()

    def _record(self, eps: list[Rollout], epsilon: float, loss: float) -> None:
        h = self.history
        n = max(len(eps), 1)
        h["phase"].append(self.phase)
        h["episode"].append(self.episode if self.phase != "il_fit" else self.epoch)
        h["time"].append(self.elapsed)
        for key in ("success", "collision", "timeout"):
            h[key].append(sum(e.outcome == key for e in eps) / n if eps else float("nan"))
        h["epsilon"].append(epsilon)
        h["loss"].append(loss)
        h["memory"].append(len(self.memory))

    def _evaluate(self) -> None:
        if not self.cfg.eval_every:
            return
        from crowdbench.evaluation import run_episodes, summarize

        with self._timed("evaluation"):
            s = summarize(run_episodes(self.policy, self.cfg.eval_episodes, seed=10**6,
                                       num_worlds=min(self.cfg.eval_episodes, 100), num_humans=20,
                                       human_model="responsive_orca",
                                       human_model_kwargs={"responsiveness": 0.5}))
        self.evals.append({"phase": self.phase, "episode": self.episode, "time": self.elapsed, **s})

    def _progress(self) -> None:
        if self.quiet:
            return
        cfg, h = self.cfg, self.history
        if self.phase == "il_fit":
            what = f"imitation epoch {self.epoch}/{cfg.il_epochs} | loss {h['loss'][-1]:.4f}"
        else:
            total = cfg.il_episodes if self.phase == "il" else cfg.rl_episodes
            recent = [x for x, p in zip(h["success"][-20:], h["phase"][-20:], strict=True) if p == self.phase]
            succ = np.nanmean(recent) if recent else float("nan")
            what = f"{self.phase} episode {self.episode}/{total} | success {succ:.2f}"
            if self.phase == "rl":
                what += f" | ε {h['epsilon'][-1]:.2f}"
        ev = f" | eval {self.evals[-1]['success_rate']:.2f}" if self.evals else ""
        line = f"{cfg.method} | {what}{ev} | memory {len(self.memory):,} | elapsed {self.elapsed / 60:5.1f} min"
        end = "\r" if sys.stdout.isatty() else "\n"
        print(line.ljust(110), end=end, flush=True)

    # ------------------------------------------------------------------ checkpoints
    def policy_checkpoint(self) -> dict[str, Any]:
        """What is shipped: the network, its architecture, the discount and where it came from."""
        from crowdbench import __version__, checkpoints
        from crowdbench.worlds.digest import crowd_digest

        return {"format": checkpoints.FORMAT, "method": self.cfg.method, "crowdbench_version": __version__,
                "crowd": crowd_digest(), "sensing": self.cfg.sensing, "model": dict(self.cfg.model),
                "gamma": self.cfg.gamma, "free_space": self.cfg.free_space,
                "n_max": self.config.max_humans_observed,
                "seed": self.cfg.seed, "phase": self.phase, "episodes": self.episode, "elapsed_s": self.elapsed,
                "train_config": self.cfg.to_dict(), "net": self.net.state_dict()}

    def save(self, figure: bool = True) -> None:
        """Write ``last.pt``, ``policy.pt``, ``history.json`` and (with ``figure``) ``curve.png``."""
        import torch

        from crowdbench import checkpoints
        from crowdbench.io import write_text
        from crowdbench.training.plots import plot_value_curve

        with self._timed("checkpoints"):
            full = {**self.policy_checkpoint(), "target": self.target.state_dict(),
                    "optimizer": self.optimizer.state_dict(), "memory": self.memory.state_dict(),
                    "rng": _encode_state(self.rng.bit_generator.state), "epoch": self.epoch,
                    "torch_rng": torch.get_rng_state(), "history": self.history, "evals": self.evals,
                    "clock": self.clock}
            checkpoints.save(full, os.path.join(self.out, "last.pt"))
            checkpoints.save(self.policy_checkpoint(), os.path.join(self.out, "policy.pt"))
            write_text(os.path.join(self.out, "history.json"),
                       json.dumps({"config": self.cfg.to_dict(), "clock_s": self.clock, "history": self.history,
                                   "evals": self.evals}) + "\n")
            if figure:
                plot_value_curve(self.history, self.evals, os.path.join(self.out, "curve.png"),
                                 title=f"{self.cfg.method} (seed {self.cfg.seed})")

    def load(self, path: str) -> None:
        """Continue the run saved in ``path`` (same configuration apart from :data:`RESUMABLE` fields)."""
        import torch

        from crowdbench import checkpoints

        ckpt = checkpoints.load(path, self.cfg.method)
        checkpoints.require_resumable(ckpt, path, "memory")
        saved = ValueTrainConfig.from_dict(ckpt["train_config"]).to_dict()
        mine = self.cfg.to_dict()
        diff = sorted(k for k in mine if k not in RESUMABLE and mine[k] != saved.get(k))
        if diff:
            raise ValueError(f"--resume: the checkpoint's configuration differs in {diff}; only "
                             f"{', '.join(RESUMABLE)} may change when resuming")
        self.net.load_state_dict(ckpt["net"])
        self.target.load_state_dict(ckpt["target"])
        self.phase, self.episode, self.epoch = ckpt["phase"], int(ckpt["episodes"]), int(ckpt["epoch"])
        self.optimizer = self._sgd(self.cfg.rl_learning_rate if self.phase in ("rl", "done")
                                   else self.cfg.il_learning_rate)
        self.optimizer.load_state_dict(ckpt["optimizer"])
        self.memory.load_state_dict(ckpt["memory"])
        self.rng.bit_generator.state = _decode_state(ckpt["rng"])
        torch.set_rng_state(ckpt["torch_rng"])
        self.elapsed = float(ckpt["elapsed_s"])
        self.history, self.evals = ckpt["history"], ckpt["evals"]
        self.clock = {**self.clock, **ckpt.get("clock", {})}


def _encode_state(state: dict[str, Any]) -> dict[str, Any]:
    """A numpy bit-generator state with its 128-bit integers as strings (checkpoint-safe)."""
    return json.loads(json.dumps(state, default=str), parse_int=str)


def _decode_state(state: dict[str, Any]) -> dict[str, Any]:
    def conv(x: Any) -> Any:
        if isinstance(x, dict):
            return {k: conv(v) for k, v in x.items()}
        return int(x) if isinstance(x, str) and x.lstrip("-").isdigit() else x

    return conv(state)


def resume_config(path: str, **changes: Any) -> ValueTrainConfig:
    """The configuration of the run saved in ``path`` with some :data:`RESUMABLE` fields changed."""
    from crowdbench import checkpoints

    bad = sorted(set(changes) - set(RESUMABLE))
    if bad:
        raise ValueError(f"--resume: {bad} cannot change; valid choices: {', '.join(RESUMABLE)}")
    ckpt = checkpoints.load(path)
    if ckpt.get("method") not in value_methods() or "train_config" not in ckpt:
        raise ValueError(f"--resume: {path!r} is not a CADRL/SARL training checkpoint")
    checkpoints.require_resumable(ckpt, path, "memory")
    return dataclasses.replace(ValueTrainConfig.from_dict(ckpt["train_config"]), **changes)


def train_value(cfg: ValueTrainConfig, out: str, resume: str | None = None, quiet: bool = False) -> ValueTrainer:
    """Train (or resume from ``resume``: a run folder or its ``last.pt``); returns the trainer."""
    trainer = ValueTrainer(cfg, out, quiet=quiet)
    if resume:
        from crowdbench import checkpoints

        trainer.load(checkpoints.run_checkpoint(resume))
    trainer.train()
    return trainer
