"""Pedestrians that learn: a shared-parameter pedestrian policy trained with rsl-rl PPO (``crowdbench train-crowd``).

Every pedestrian of every world is a row of the batch (:class:`CrowdAgentsVecEnv` over the batched multi-agent
interface, :class:`~crowdbench.envs.marl.CrowdMARLEnv`): circle crossing, no robot, 10–20 pedestrians per world,
the ``progress`` pedestrian reward (:mod:`crowdbench.humans.rewards`) with a stiffer contact cost
(:class:`CrowdTrainConfig`). A row's episode ends when its pedestrian
arrives (the slot is then a new person: re-spawned) or when its world's episode ends (a time-out). The actor and
critic are rsl-rl ``MLPModel`` s over goal-aligned features (:func:`crowdbench.humans.learned.features`); the
Gaussian action is squashed by ``tanh`` to the normalised action box. The result ships, weights only, as the
``learned_crowd`` pedestrian model.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import torch
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from crowdbench.envs.marl import CrowdMARLEnv
from crowdbench.envs.parallel import disc_velocity, square
from crowdbench.humans.learned import FEATURES, features, observe, to_world
from crowdbench.io import write_text


@dataclass(frozen=True)
class CrowdTrainConfig:
    """Recipe of ``crowdbench train-crowd`` (every field recorded in the checkpoint)."""

    seed: int = 0
    worlds: int = 32
    """Worlds stepped together [-]."""
    humans: int = 20
    """Pedestrian slots per world [-]."""
    steps_per_env: int = 32
    """Rollout length per iteration [steps]."""
    iterations: int = 300
    hidden: tuple[int, ...] = (128, 128)
    learning_rate: float = 1e-3
    entropy_coef: float = 0.005
    init_std: float = 0.6
    w_collision: float = -4.0
    """The ``progress`` reward's contact cost per step [-] (its default, −1, let 20-person crossings bump: a crowd
    worth using keeps its people apart)."""
    personal: float = 0.2
    """The ``progress`` reward's personal distance [m]."""
    w_intrusion: float = -1.0
    """The ``progress`` reward's intrusion weight [1/m]."""
    w_time: float = -0.05
    """The ``progress`` reward's cost per step [-] (its default, −0.01, made standing still nearly free: a run
    with it learned to wait out every crossing)."""
    threads: int = 1

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["hidden"] = list(self.hidden)
        return d


class CrowdAgentsVecEnv(VecEnv):
    """rsl-rl ``VecEnv`` whose rows are the pedestrian slots of ``worlds`` crowd worlds (module docstring)."""

    def __init__(self, cfg: CrowdTrainConfig) -> None:
        from crowdbench.humans.rewards import Progress

        reward = Progress(w_collision=cfg.w_collision, personal=cfg.personal, w_intrusion=cfg.w_intrusion,
                          w_time=cfg.w_time)
        self.marl = CrowdMARLEnv(num_worlds=cfg.worlds, num_humans=cfg.humans, robot=None, device=None,
                                 seed=cfg.seed, max_cycles=200, human_reward=reward)
        self.num_envs = cfg.worlds * cfg.humans
        self.num_actions = 2
        self.max_episode_length = 200
        self.device = "cpu"
        self.cfg = cfg.to_dict()
        self.episode_length_buf = torch.zeros(self.num_envs, dtype=torch.long)
        self.marl.reset(cfg.seed)
        self._stats = {"arrivals": 0.0, "contacts": 0.0, "steps": 0.0}

    def _obs(self) -> TensorDict:
        w = self.marl.world
        me, nb, mask = observe(w.pos, w.vel, w.goal, w.radius, w.v_pref, w.heading, w.active, False)
        self._me = me[:, 1:].astype(np.float64)  # the frame each pedestrian's next action is given in
        x = features(me[:, 1:], nb[:, 1:], mask[:, 1:]).reshape(self.num_envs, FEATURES)
        return TensorDict({"policy": torch.from_numpy(x)}, batch_size=[self.num_envs])

    def get_observations(self) -> TensorDict:
        return self._obs()

    def step(self, actions: torch.Tensor):
        a = torch.tanh(actions.detach()).reshape(self.marl.num_worlds, self.marl.num_agents, 2).numpy()
        # goal frame → world frame: rotating the square would leave it; rotate the disc velocity, then invert the
        # map back to the world-frame normalised action the interface takes
        v = to_world(disc_velocity(a.astype(np.float64), np.ones(a.shape[:2])), self._me)
        _, rew, done, info = self.marl.step(square(v))
        arrived = np.asarray(info["arrived"]).reshape(-1)
        world_done = np.repeat(np.asarray(done), self.marl.num_agents)
        dones = arrived | world_done
        self.episode_length_buf += 1
        self.episode_length_buf[torch.from_numpy(dones)] = 0
        self._stats["arrivals"] += float(arrived.sum())
        self._stats["contacts"] += float(np.asarray(info["contacts"]).sum())
        self._stats["steps"] += float(self.marl.world.active[:, 1:].sum())
        extras = {"time_outs": torch.from_numpy(world_done & ~arrived), "log": self.log()}
        return self._obs(), torch.from_numpy(np.asarray(rew, np.float32).reshape(-1)), torch.from_numpy(dones), extras

    def log(self) -> dict[str, float]:
        s = max(self._stats["steps"], 1.0)
        return {"Crowd/arrivals_per_1k_steps": 1000 * self._stats["arrivals"] / s,
                "Crowd/contacts_per_1k_steps": 1000 * self._stats["contacts"] / s}


def train(cfg: CrowdTrainConfig, out: str, quiet: bool = False) -> dict[str, Any]:
    """Train and write ``OUT/learned_crowd.pt`` (weights, config, provenance) and ``OUT/history.json``."""
    from rsl_rl.runners import OnPolicyRunner

    from crowdbench import __version__
    from crowdbench.worlds.digest import crowd_digest

    torch.manual_seed(cfg.seed)
    torch.set_num_threads(cfg.threads)
    os.makedirs(out, exist_ok=True)
    env = CrowdAgentsVecEnv(cfg)
    model = {"class_name": "MLPModel", "hidden_dims": list(cfg.hidden), "activation": "elu"}
    train_cfg = {
        "num_steps_per_env": cfg.steps_per_env, "save_interval": 10 ** 9, "obs_groups": {"actor": ["policy"],
                                                                                        "critic": ["policy"]},
        "algorithm": {"class_name": "PPO", "num_learning_epochs": 4, "num_mini_batches": 8, "clip_param": 0.2,
                      "gamma": 0.98, "lam": 0.95, "value_loss_coef": 1.0, "entropy_coef": cfg.entropy_coef,
                      "learning_rate": cfg.learning_rate, "max_grad_norm": 1.0, "schedule": "adaptive",
                      "desired_kl": 0.01},
        "actor": {**model, "distribution_cfg": {"class_name": "GaussianDistribution", "init_std": cfg.init_std,
                                                 "std_type": "scalar"}},
        "critic": dict(model),
    }
    runner = OnPolicyRunner(env, train_cfg, log_dir=None, device="cpu")
    history: list[dict[str, float]] = []
    t0 = time.time()
    chunk = 10
    for it in range(0, cfg.iterations, chunk):
        env._stats = {"arrivals": 0.0, "contacts": 0.0, "steps": 0.0}
        runner.learn(min(chunk, cfg.iterations - it))
        row = {"iteration": it + chunk, "minutes": (time.time() - t0) / 60, **env.log()}
        history.append(row)
        if not quiet:
            print(f"it {row['iteration']:>5} | arrivals {row['Crowd/arrivals_per_1k_steps']:.2f} / 1k ped-steps | "
                  f"contacts {row['Crowd/contacts_per_1k_steps']:.2f} / 1k | {row['minutes']:.1f} min", flush=True)
    actor = runner.alg.actor
    names = [n.rsplit(".", 1)[0] for n, p in actor.named_parameters() if n.endswith(".weight") and "mlp" in n]
    state = {k: v.detach().clone() for k, v in actor.state_dict().items() if k.rsplit(".", 1)[0] in names}
    ckpt = {"format": "crowdbench.checkpoint/2", "method": "learned_crowd", "crowdbench_version": __version__,
            "crowd": crowd_digest(), "train_config": cfg.to_dict(), "features": FEATURES,
            "layer_names": names, "mean_layers": state, "history": history,
            "env_steps": cfg.iterations * cfg.steps_per_env * env.num_envs}
    from crowdbench import checkpoints

    checkpoints.save(ckpt, os.path.join(out, "learned_crowd.pt"))
    write_text(os.path.join(out, "history.json"), json.dumps(history, indent=1) + "\n")
    plot_history(history, os.path.join(out, "curve.png"))
    return ckpt


def plot_history(history: list[dict[str, float]], path: str) -> None:
    """The training curve: goal arrivals and contacts per 1,000 pedestrian-steps (stochastic policy) against
    iterations, written atomically as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crowdbench.io import atomic_path

    it = [h["iteration"] for h in history]
    fig, ax = plt.subplots(figsize=(6, 3.2))
    ax.plot(it, [h["Crowd/arrivals_per_1k_steps"] for h in history], label="goal arrivals")
    ax.plot(it, [h["Crowd/contacts_per_1k_steps"] for h in history], label="pedestrians in contact")
    ax.set_xlabel("PPO iteration")
    ax.set_ylabel("per 1,000 pedestrian-steps")
    ax.set_yscale("log")
    ax.legend()
    ax.set_title("learned_crowd training (stochastic policy)")
    fig.tight_layout()
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png", dpi=120)
    plt.close(fig)
