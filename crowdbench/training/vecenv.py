"""rsl-rl ``VecEnv`` over a batch of crowd worlds, with the paper's responsiveness-annealing curriculum
(:mod:`crowdbench.training.curriculum`).

Robot only; pedestrians are driven by the world's pedestrian model (latent-responsive ORCA for H²INT).
Same-step auto-reset; ``extras["time_outs"]`` marks truncations; observations are a TensorDict of the groups
``robot`` ``(B, 9)``, ``humans`` ``(B, N_max, 2)`` and ``mask`` ``(B, N_max)``.
"""

from __future__ import annotations

from collections import deque
from typing import Any

import numpy as np
import torch
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from crowdbench.config import make_config
from crowdbench.training.curriculum import Curriculum
from crowdbench.training.shards import ShardedWorlds, ShardSpec, StepOut
from crowdbench.worlds.world import COLLISION, SUCCESS, TIMEOUT


class CrowdVecEnv(VecEnv):
    """``num_envs`` crowd worlds as one rsl-rl environment.

    Args:
        num_envs: Worlds stepped together.
        seed: Master seed; world ``w`` draws its episode seeds from stream ``w`` of
            ``np.random.SeedSequence(seed).spawn(num_envs)``.
        curriculum: Responsiveness schedule; its current ρ applies to every episode that starts.
        reward_scale: Multiplies the rewards handed to PPO (outcomes and metrics are unaffected).
        processes: 1 steps every world in this process; ``k ≥ 2`` splits them into ``k`` groups, each stepped by a
            worker process (:class:`~crowdbench.training.shards.ShardedWorlds`), in parallel by :meth:`step`, or
            group by group, each group's process acting too, with :meth:`act_async` / :meth:`act_wait`
            (:mod:`crowdbench.training.rollout`). The same numbers for any value. Call :meth:`close` when done.
        start_method: Worker-process start method (default: ``fork`` where available, else ``spawn``).
        layout, human_model, human_model_kwargs: As for :class:`~crowdbench.worlds.CrowdWorld`.
        observation: The robot observation the policy reads (:data:`crowdbench.robots.OBSERVATIONS`).
        observation_kwargs: Its builder's options (e.g. ``predicted``'s ``predictor``).
        **world_options: :class:`~crowdbench.config.WorldConfig` fields (e.g. ``humans_range=(10, 30)``).
    """

    def __init__(self, num_envs: int = 128, seed: int = 0, curriculum: Curriculum | None = None,
                 layout: str = "circle_crossing", human_model: str = "responsive_orca",
                 human_model_kwargs: dict | None = None, reward_scale: float = 1.0, processes: int = 1,
                 start_method: str | None = None, observation: str = "relative",
                 observation_kwargs: dict[str, Any] | None = None, **world_options: Any) -> None:
        if processes < 1:
            raise ValueError(f"processes={processes}; valid choices: 1 (this process) or ≥ 2 (worker processes)")
        self.reward_scale = reward_scale
        self.curriculum = curriculum or Curriculum(enabled=False)
        kwargs = {"responsiveness": self.curriculum.rho, **(human_model_kwargs or {})}
        self.config = make_config(**world_options)
        spec = ShardSpec(self.config, num_envs, layout, human_model, kwargs, observation=observation,
                         observation_kwargs=dict(observation_kwargs or {}))
        self.worlds = ShardedWorlds(spec, seed, processes, local=processes == 1, start_method=start_method)
        self.groups = self.worlds.slices
        """The world slices stepped by each process (one slice when ``processes == 1``)."""
        self.num_envs = num_envs
        self.num_actions = 2
        self.max_episode_length = self.config.max_steps
        self.device = "cpu"
        self.cfg = {"layout": layout, "human_model": human_model, "seed": seed, **world_options}
        self.episode_length_buf = torch.zeros(num_envs, dtype=torch.long)
        self.episodes = 0
        self.totals = np.zeros(4, dtype=np.int64)  # outcome counts
        self.window_outcomes: deque[int] = deque(maxlen=self.curriculum.window)
        self._obs: list[dict[str, np.ndarray]] = [{} for _ in self.groups]
        self.reset_all()

    def reset_all(self) -> None:
        """Start fresh episodes in every world (next seed of each world's stream)."""
        out = self.worlds.reset_all(self.curriculum.rho)
        self._store_obs(None, out.obs)
        self.episode_length_buf = torch.from_numpy(out.steps)

    def _store_obs(self, k: int | None, obs: dict[str, np.ndarray]) -> None:
        """Keep group ``k``'s latest observations (``None``: ``obs`` covers every world)."""
        if k is None:
            for j, g in enumerate(self.groups):
                self._obs[j] = {key: v[g] for key, v in obs.items()}
        else:
            self._obs[k] = obs

    def get_observations(self) -> TensorDict:
        """Current observations of every world (a new TensorDict each call: rollouts keep references)."""
        obs = {k: torch.from_numpy(np.concatenate([o[k] for o in self._obs])) for k in self._obs[0]}
        return TensorDict(obs, batch_size=[self.num_envs])

    def _finish(self, k: int | None, out: StepOut) -> tuple[TensorDict, torch.Tensor, torch.Tensor, dict]:
        """Book-keeping of a finished step of group ``k`` (None: every world); rsl-rl's step tuple for it."""
        sl = slice(None) if k is None else self.groups[k]
        done = out.terminated | out.truncated
        if done.any():
            outcomes = out.outcome[done]
            self.episodes += len(outcomes)
            self.totals += np.bincount(outcomes, minlength=4)
            self.window_outcomes.extend(int(o) for o in outcomes)
            self.curriculum.record(outcomes == SUCCESS, self.episodes)
        self._store_obs(k, out.obs)
        self.episode_length_buf[sl] = torch.from_numpy(out.steps)
        extras = {"time_outs": torch.from_numpy(out.truncated), "log": self.log()}
        rewards = torch.from_numpy((out.reward * self.reward_scale).astype(np.float32))
        obs = TensorDict({key: torch.from_numpy(v) for key, v in out.obs.items()}, batch_size=[len(done)])
        return obs, rewards, torch.from_numpy(done), extras

    def log(self) -> dict[str, float]:
        """Outcome rates over the last ``window`` episodes and the current ρ."""
        w = np.asarray(self.window_outcomes) if self.window_outcomes else np.zeros(1, dtype=int) - 1
        return {"Crowd/rho": self.curriculum.rho, "Crowd/success_rate": float(np.mean(w == SUCCESS)),
                "Crowd/collision_rate": float(np.mean(w == COLLISION)),
                "Crowd/timeout_rate": float(np.mean(w == TIMEOUT))}

    def step(self, actions: torch.Tensor):
        """Step every world (same-step auto-reset); rsl-rl's ``(obs, rewards, dones, extras)``."""
        out = self.worlds.step(actions.detach().cpu().numpy().astype(np.float64), self.episode_length_buf.numpy(),
                               self.curriculum.rho)
        return self._finish(None, out)

    def act_async(self, k: int, noise: np.ndarray) -> None:
        """Start group ``k``'s act-and-step with the policy installed in its process
        (:mod:`crowdbench.training.acting`) and its worlds' Gaussian noise ``(n_k, 2)``."""
        self.worlds.send_act_step(k, noise, self.episode_length_buf[self.groups[k]].numpy(), self.curriculum.rho)

    def act_wait(self, k: int):
        """Finish group ``k``'s act-and-step: ``(obs, rewards, dones, extras, record, next_state)``."""
        out, record, state = self.worlds.wait(k)
        return (*self._finish(k, out), record, state)

    def close(self) -> None:
        """Stop the worker processes (if any)."""
        self.worlds.close()

    def state_dict(self) -> dict[str, Any]:
        """Curriculum, outcome statistics and every world's seed stream (worlds restart at a checkpoint)."""
        return {"curriculum": self.curriculum.state_dict(), "streams": self.worlds.get_streams(),
                "episodes": self.episodes, "totals": self.totals.tolist(), "window": list(self.window_outcomes)}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        if "streams" not in d:
            raise ValueError("this checkpoint comes from an older crowdbench (one master seed stream) and cannot be "
                             "resumed exactly; start a new run")
        self.curriculum.load_state_dict(d["curriculum"])
        self.worlds.set_streams(d["streams"])
        self.episodes = int(d["episodes"])
        self.totals = np.asarray(d["totals"], dtype=np.int64)
        self.window_outcomes = deque((int(x) for x in d["window"]), maxlen=self.curriculum.window)
