"""rsl-rl ``VecEnv`` over a batch of crowd worlds, with the paper's responsiveness-annealing curriculum.

Robot only; pedestrians are driven by the world's pedestrian model (latent-responsive ORCA for H²INT).
Same-step auto-reset; ``extras["time_outs"]`` marks truncations; observations are a TensorDict of the groups
``robot`` ``(B, 9)``, ``humans`` ``(B, N_max, 2)`` and ``mask`` ``(B, N_max)``.
"""

from __future__ import annotations

from collections import deque
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import torch
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from crowdbench.config import make_config
from crowdbench.training.shards import ShardedWorlds, ShardSpec
from crowdbench.worlds.world import COLLISION, SUCCESS, TIMEOUT


@dataclass
class Curriculum:
    """Responsiveness annealing (§Training Strategy): start at ``rho_init``; whenever the success rate over the last
    ``window`` episodes — all finished at the current ρ — is ≥ ``eta`` and ``cooldown`` episodes have finished since
    the last change, ρ ← max(ρ − ``delta``, ``rho_min``). ``enabled=False`` keeps ρ fixed (``--no-anneal``)."""

    rho_init: float = 0.8
    rho_min: float = 0.0
    delta: float = 0.1
    eta: float = 0.9
    window: int = 200
    cooldown: int = 200
    enabled: bool = True

    def __post_init__(self) -> None:
        self.rho = self.rho_init
        self.recent: deque[bool] = deque(maxlen=self.window)
        self.since_change = 0
        self.changes: list[tuple[int, float]] = []

    def record(self, successes: np.ndarray, episodes_total: int) -> bool:
        """Add finished episodes' outcomes; returns True when ρ was lowered."""
        self.recent.extend(bool(s) for s in successes)
        self.since_change += len(successes)
        if (self.enabled and self.rho > self.rho_min + 1e-9 and len(self.recent) == self.window
                and self.since_change >= self.cooldown and np.mean(self.recent) >= self.eta):
            self.rho = round(max(self.rho - self.delta, self.rho_min), 10)
            self.recent.clear()
            self.since_change = 0
            self.changes.append((episodes_total, self.rho))
            return True
        return False

    def state_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d.update(rho=self.rho, recent=list(self.recent), since_change=self.since_change,
                 changes=[list(c) for c in self.changes])
        return d

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.rho, self.since_change = float(d["rho"]), int(d["since_change"])
        self.recent = deque((bool(x) for x in d["recent"]), maxlen=self.window)
        self.changes = [(int(a), float(b)) for a, b in d["changes"]]


class CrowdVecEnv(VecEnv):
    """``num_envs`` crowd worlds as one rsl-rl environment.

    Args:
        num_envs: Worlds stepped together.
        seed: Master seed; episode seeds are drawn from ``np.random.default_rng(seed)``, in world order.
        curriculum: Responsiveness schedule (its ρ is applied at every episode start).
        reward_scale: Multiplies the rewards handed to PPO (outcomes and metrics are unaffected).
        processes: Processes stepping the worlds (:class:`~crowdbench.training.shards.ShardedWorlds`; the same
            numbers for any value). Call :meth:`close` when done with more than one.
        layout, human_model, human_model_kwargs: As for :class:`~crowdbench.worlds.CrowdWorld`.
        **world_options: :class:`~crowdbench.config.WorldConfig` fields (e.g. ``humans_range=(10, 30)``).
    """

    def __init__(self, num_envs: int = 128, seed: int = 0, curriculum: Curriculum | None = None,
                 layout: str = "circle_crossing", human_model: str = "responsive_orca",
                 human_model_kwargs: dict | None = None, reward_scale: float = 1.0, processes: int = 1,
                 **world_options: Any) -> None:
        self.reward_scale = reward_scale
        self.curriculum = curriculum or Curriculum(enabled=False)
        kwargs = {"responsiveness": self.curriculum.rho, **(human_model_kwargs or {})}
        self.config = make_config(**world_options)
        self.worlds = ShardedWorlds(ShardSpec(self.config, num_envs, layout, human_model, kwargs), processes)
        self.num_envs = num_envs
        self.num_actions = 2
        self.max_episode_length = self.config.max_steps
        self.device = "cpu"
        self.cfg = {"layout": layout, "human_model": human_model, "seed": seed, **world_options}
        self.master = np.random.default_rng(seed)
        self.episode_length_buf = torch.zeros(num_envs, dtype=torch.long)
        self.episodes = 0
        self.totals = np.zeros(4, dtype=np.int64)  # outcome counts
        self.window_outcomes: deque[int] = deque(maxlen=self.curriculum.window)
        self.reset_all()

    def _seeds(self, k: int) -> list[int]:
        return [int(s) for s in self.master.integers(0, 2**63 - 1, k)]

    def reset_all(self) -> None:
        """Start fresh episodes in every world (seeds from the master generator)."""
        self._set_obs(*self.worlds.reset(self._seeds(self.num_envs), None, self.curriculum.rho))

    def _set_obs(self, obs: dict[str, np.ndarray], steps: np.ndarray) -> None:
        self._obs = TensorDict({k: torch.from_numpy(v) for k, v in obs.items()}, batch_size=[self.num_envs])
        self.episode_length_buf = torch.from_numpy(steps)

    def get_observations(self) -> TensorDict:
        return self._obs

    def step(self, actions: torch.Tensor):
        reward, terminated, truncated, outcome = self.worlds.step(
            actions.detach().cpu().numpy().astype(np.float64), self.episode_length_buf.numpy())
        done = terminated | truncated
        log: dict[str, float] = {"rho": self.curriculum.rho}
        seeds: list[int] = []
        if done.any():
            outcomes = outcome[done]
            self.episodes += len(outcomes)
            self.totals += np.bincount(outcomes, minlength=4)
            self.window_outcomes.extend(int(o) for o in outcomes)
            self.curriculum.record(outcomes == SUCCESS, self.episodes)
            seeds = self._seeds(int(done.sum()))
        self._set_obs(*self.worlds.reset(seeds, done, self.curriculum.rho))
        w = np.asarray(self.window_outcomes) if self.window_outcomes else np.zeros(1, dtype=int) - 1
        log.update(success_rate=float(np.mean(w == SUCCESS)), collision_rate=float(np.mean(w == COLLISION)),
                   timeout_rate=float(np.mean(w == TIMEOUT)))
        extras = {"time_outs": torch.from_numpy(truncated), "log": {f"Crowd/{k}": v for k, v in log.items()}}
        rewards = torch.from_numpy((reward * self.reward_scale).astype(np.float32))
        return self.get_observations(), rewards, torch.from_numpy(done), extras

    def close(self) -> None:
        """Stop the worker processes (if any)."""
        self.worlds.close()

    def state_dict(self) -> dict[str, Any]:
        """Curriculum, outcome statistics and the master generator (worlds restart at a checkpoint)."""
        return {"curriculum": self.curriculum.state_dict(), "master": self.master.bit_generator.state,
                "episodes": self.episodes, "totals": self.totals.tolist(), "window": list(self.window_outcomes)}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.curriculum.load_state_dict(d["curriculum"])
        self.master.bit_generator.state = d["master"]
        self.episodes = int(d["episodes"])
        self.totals = np.asarray(d["totals"], dtype=np.int64)
        self.window_outcomes = deque((int(x) for x in d["window"]), maxlen=self.curriculum.window)
