"""CADRL and SARL as crowdbench robot policies: a trained value network acting greedily through the one-step
look-ahead (:mod:`crowdbench.policies.value.lookahead`)."""

from __future__ import annotations

import os
from typing import Any, ClassVar

import numpy as np
import torch

from crowdbench import checkpoints
from crowdbench.config import WorldConfig
from crowdbench.policies.base import RobotPolicy
from crowdbench.policies.value.lookahead import Scene, action_set, action_values
from crowdbench.policies.value.model import build_net
from crowdbench.robots.observations import STATE_OBSERVATIONS, check_sensing

GAMMA = 0.9
"""CrowdNav's discount, applied as γ^{Δt·v_pref} per step."""


def load_net(method: str, checkpoint: str | os.PathLike | None = None) -> tuple[torch.nn.Module, dict[str, Any]]:
    """The value network of a ``method`` checkpoint (path, shipped name, or None for the shipped default) in eval
    mode, and its metadata (gamma, seed, episodes, path)."""
    path = checkpoints.resolve(method, checkpoint)
    ckpt = checkpoints.load(path, method)
    net = build_net(method, ckpt["model"])
    net.load_state_dict(ckpt["net"])
    meta = {k: ckpt.get(k) for k in ("seed", "episodes", "phase", "sensing")}
    return net.eval(), {**meta, "gamma": float(ckpt.get("gamma", GAMMA)),
                        "free_space": bool(ckpt.get("free_space", False)), "path": path}


class ValuePolicy(RobotPolicy):
    """Greedy one-step look-ahead on a value network (CrowdNav's ``MultiHumanRL.predict``), batched over worlds.

    Args:
        config: World configuration (time step, goal tolerance, sensing range).
        checkpoint: Path or shipped name (default: the shipped checkpoint named like the method).
        net: Alternatively a live network (training).
        gamma: Discount per second at v_pref = 1 (default: the checkpoint's, else 0.9).
        sensing: Sensing tier (``positions``: velocities estimated from positions; ``velocities``; ``full``;
            default: the checkpoint's, ``velocities`` for checkpoints that do not say — they were trained on true
            velocities).
        sensing_range: Pedestrians beyond this centre distance are not considered [m] (default: no limit beyond
            the observation's own sensing range).
        free_space: Value states with nobody sensed analytically
            (:func:`~crowdbench.policies.value.lookahead.free_space_value`; default: as the checkpoint was trained,
            ``False`` for checkpoints that do not say).
    """

    observation = "estimated_state"
    stateless = True
    method: ClassVar[str] = ""

    def __init__(self, config: WorldConfig | None = None, checkpoint: str | None = None,
                 net: torch.nn.Module | None = None, gamma: float | None = None, sensing: str | None = None,
                 sensing_range: float | None = None, free_space: bool | None = None) -> None:
        super().__init__(config)
        self.meta: dict[str, Any] = {}
        if net is None:
            net, self.meta = load_net(self.method, checkpoint)
        self.net = net
        tier = sensing if sensing is not None else (self.meta.get("sensing") or ("velocities" if self.meta
                                                                                   else "positions"))
        self.observation = STATE_OBSERVATIONS[check_sensing(tier, f"robot policy {self.method}: sensing")]
        self.gamma = float(gamma if gamma is not None else self.meta.get("gamma", GAMMA))
        if not 0.0 < self.gamma <= 1.0:
            raise ValueError(f"gamma={self.gamma}; valid choices: a number in (0, 1]")
        self.sensing_range = float(sensing_range if sensing_range is not None else np.inf)
        self.free_space = bool(free_space if free_space is not None else self.meta.get("free_space", False))
        self.actions = torch.as_tensor(action_set(), dtype=torch.float32)

    @torch.inference_mode()
    def plan(self, obs: dict[str, np.ndarray], epsilon: float = 0.0,
             rng: np.random.Generator | None = None) -> tuple[np.ndarray, Scene]:
        """Greedy actions ``(B, 2)`` [m/s] (with probability ``epsilon`` per world a uniformly random one of the 81,
        drawn from ``rng``) and the scenes they were chosen in."""
        scene = Scene.from_obs(obs, self.sensing_range)
        cfg = self.config
        q = action_values(self.net, scene, self.actions, cfg.time_step, self.gamma, cfg.reward.goal_tolerance,
                          self.free_space)
        idx = q.argmax(dim=1).numpy()
        if epsilon > 0.0:
            if rng is None:
                raise ValueError("plan: epsilon > 0 needs rng (a numpy Generator)")
            explore = rng.random(len(idx)) < epsilon
            idx = np.where(explore, rng.integers(0, len(self.actions), len(idx)), idx)
        act = self.actions.numpy()[idx] * obs["robot"][:, 5:6]
        return act.astype(np.float64), scene

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return self.plan(obs)[0]


class CADRLPolicy(ValuePolicy):
    """CADRL (Chen et al. 2017): pairwise value network, min over pedestrians (registered ``cadrl``)."""

    method = "cadrl"


class SARLPolicy(ValuePolicy):
    """SARL (Chen et al. 2019): self-attention over the crowd (registered ``sarl``)."""

    method = "sarl"
