"""A batch of crowd worlds split into shards, stepped in this process or in worker processes.

Every world draws its episode seeds from its own stream (``np.random.SeedSequence(seed).spawn(num_worlds)``), and a
shard resets its finished worlds itself, right after the step that finished them (same-step auto-reset) — one round
trip per step, and the numbers do not depend on how the batch is split: any sharding gives exactly the same
rollouts for the same actions (tested).

Worker processes are started with ``fork`` where the platform has it (Linux), so pedestrian models registered at run
time are visible to them, and with ``spawn`` elsewhere (macOS, Windows) or when asked (``start_method="spawn"``,
tested): then register your own models through the ``crowdbench.humans`` entry point, which a fresh interpreter sees.
"""

from __future__ import annotations

import multiprocessing as mp
import pickle
import traceback
from dataclasses import dataclass, field, replace
from multiprocessing.connection import Connection
from typing import Any

import numpy as np

from crowdbench.config import WorldConfig
from crowdbench.robots.observations import make_observation
from crowdbench.worlds.world import CrowdWorld


@dataclass
class ShardSpec:
    """What a shard needs to build its worlds."""

    config: WorldConfig
    num_worlds: int
    layout: str
    human_model: str
    human_model_kwargs: dict[str, Any]
    observation: str = "relative"
    observation_kwargs: dict[str, Any] = field(default_factory=dict)
    """Options of the observation builder (e.g. ``predicted``'s predictor)."""


@dataclass
class StepOut:
    """One shard's (or the whole batch's) step: arrays with the worlds as leading dimension."""

    reward: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray
    outcome: np.ndarray
    obs: dict[str, np.ndarray]
    """Observations after the same-step resets."""
    steps: np.ndarray
    """Episode step counters after the same-step resets."""


class Shard:
    """Some worlds, their seed streams and their robot-observation builder."""

    def __init__(self, spec: ShardSpec, streams: list[np.random.SeedSequence]) -> None:
        self.world = CrowdWorld(spec.config, spec.num_worlds, spec.layout, spec.human_model,
                                spec.human_model_kwargs)
        self.obs_builder = make_observation(spec.observation, spec.config, **spec.observation_kwargs)
        self.streams = [np.random.default_rng(s) for s in streams]
        self.last_obs: dict[str, np.ndarray] = {}
        self.policy: Any = None
        """What :meth:`act_step` acts with (:class:`crowdbench.training.rollout.RolloutPolicy`)."""
        self.policy_state: Any = None
        """The policy's recurrent state for these worlds (kept across :meth:`set_policy`; zeroed by resets)."""

    def _set_rho(self, rho: float | None) -> None:
        model = self.world.human_model
        if rho is not None and hasattr(model, "set_responsiveness"):
            model.set_responsiveness(rho)

    def _reset(self, mask: np.ndarray | None) -> None:
        idx = range(self.world.num_worlds) if mask is None else np.flatnonzero(mask)
        seeds = [int(self.streams[i].integers(0, 2**63 - 1)) for i in idx]
        if seeds:
            self.world.reset(seeds=seeds, mask=mask)

    def reset_all(self, rho: float | None) -> StepOut:
        """New episodes everywhere (next seed of each world's stream; ``rho`` = the crowd's mean responsiveness for
        models that have one)."""
        self._set_rho(rho)
        self._reset(None)
        n = self.world.num_worlds
        self.policy_state = None
        z = np.zeros(n, dtype=bool)
        return StepOut(np.zeros(n), z, z, np.zeros(n, dtype=np.int64), *self.observe())

    def step(self, actions: np.ndarray, steps: np.ndarray, rho: float | None) -> StepOut:
        """Step with ``actions`` ``(n, 2)`` and episode step counters ``steps`` ``(n,)``; finished worlds restart
        (with mean responsiveness ``rho``) before the observations are taken."""
        self.world.steps[:] = steps
        res = self.world.step(actions)
        done = res.terminated | res.truncated
        if done.any():
            self._set_rho(rho)
            self._reset(done)
        obs, counters = self.observe()
        reward, extra = res.reward, self.obs_builder.reward(obs)
        if extra is not None:  # the observation's own term (AIG-GST), on steps that did not end an episode
            reward = reward + np.where(done, 0.0, extra)
        return StepOut(reward, res.terminated, res.truncated, res.outcome, obs, counters)

    def observe(self) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """Robot observations and the episode step counters."""
        self.last_obs = self.obs_builder.build(self.world)
        return self.last_obs, self.world.steps.copy()

    def set_policy(self, snapshot: Any) -> None:
        """Take the weights :meth:`act_step` acts with (a :class:`~crowdbench.training.rollout.PolicySnapshot`
        before every rollout, pickled for a worker process; the recurrent state stays). Worker processes use one
        intra-op torch thread, as training does."""
        from crowdbench.training.rollout import RolloutPolicy

        if isinstance(snapshot, bytes):  # pickled by the training process
            if self.policy is None:
                import torch

                torch.set_num_threads(1)
            snapshot = pickle.loads(snapshot)  # noqa: S301 - from our own parent process
        if self.policy is None:
            self.policy = RolloutPolicy(snapshot)
        else:
            self.policy.load(snapshot)

    def act_step(self, noise: np.ndarray, steps: np.ndarray, rho: float | None
                 ) -> tuple[StepOut, dict[str, np.ndarray], np.ndarray]:
        """Act on the last observations with the installed policy and the standard-normal ``noise`` ``(n, 2)``,
        then :meth:`step`; returns the step, the policy's transition record and its next recurrent state (zeroed
        for worlds that finished)."""
        if self.policy_state is None:
            self.policy_state = self.policy.initial_state(self.world.num_worlds)
        actions, record, state = self.policy.act(self.last_obs, self.policy_state, noise)
        out = self.step(actions, steps, rho)
        state[:, out.terminated | out.truncated] = 0.0  # finished episodes start from a zero state
        self.policy_state = state
        return out, record, self.policy_state

    def get_streams(self) -> list[dict]:
        return [g.bit_generator.state for g in self.streams]

    def set_streams(self, states: list[dict]) -> None:
        for g, s in zip(self.streams, states, strict=True):
            g.bit_generator.state = s


def _worker(conn: Connection, spec: ShardSpec, streams: list[np.random.SeedSequence]) -> None:
    try:
        shard = Shard(spec, streams)
        conn.send(("ok", None))
    except Exception:  # noqa: BLE001 - reported to the parent
        conn.send(("error", traceback.format_exc()))
        return
    while True:
        try:
            method, args = conn.recv()
        except EOFError:
            return
        if method == "close":
            return
        try:
            conn.send(("ok", getattr(shard, method)(*args)))
        except Exception:  # noqa: BLE001 - reported to the parent
            conn.send(("error", traceback.format_exc()))


class ShardedWorlds:
    """``spec.num_worlds`` worlds in ``shards`` contiguous slices.

    Args:
        spec: What every shard builds (``num_worlds`` is the total).
        seed: Master seed of the per-world episode-seed streams.
        shards: Number of slices.
        local: Step the first slice in this process (the others in worker processes); ``False`` puts every slice in
            a worker, so that this process is free while they step.
        start_method: ``"fork"``, ``"spawn"`` or ``"forkserver"``; default: ``fork`` where available, else ``spawn``.
    """

    def __init__(self, spec: ShardSpec, seed: int = 0, shards: int = 1, local: bool = True,
                 start_method: str | None = None) -> None:
        if not 1 <= shards <= spec.num_worlds:
            raise ValueError(f"shards={shards}; valid choices: 1 … num_worlds ({spec.num_worlds})")
        methods = mp.get_all_start_methods()
        if start_method is not None and start_method not in methods:
            raise ValueError(f"start_method={start_method!r}; valid choices: {', '.join(methods)}")
        self.num_worlds = spec.num_worlds
        sizes = [len(a) for a in np.array_split(np.arange(spec.num_worlds), shards)]
        self.bounds = np.cumsum([0, *sizes])
        self.slices = [slice(int(a), int(b)) for a, b in zip(self.bounds[:-1], self.bounds[1:], strict=True)]
        streams = np.random.SeedSequence(seed).spawn(spec.num_worlds)
        self.local = Shard(replace(spec, num_worlds=sizes[0]), streams[self.slices[0]]) if local else None
        self._local_result: Any = None  # the local shard's result between send() and wait()
        ctx = mp.get_context(start_method or ("fork" if "fork" in methods else "spawn"))
        self.conns: list[Connection | None] = [None] if local else []
        self.procs: list[Any] = []
        for k in range(1 if local else 0, shards):
            parent, child = ctx.Pipe()
            p = ctx.Process(target=_worker, args=(child, replace(spec, num_worlds=sizes[k]), streams[self.slices[k]]),
                            daemon=True, name=f"crowdbench-shard-{k}")
            p.start()
            child.close()
            self.conns.append(parent)
            self.procs.append(p)
        for c in self.conns:
            if c is not None:
                self._recv(c)

    @property
    def world(self) -> CrowdWorld:
        """The in-process shard's worlds (all of them with one local shard)."""
        if self.local is None:
            raise AttributeError("every shard runs in a worker process")
        return self.local.world

    @staticmethod
    def _recv(conn: Connection) -> Any:
        try:
            status, value = conn.recv()
        except (EOFError, ConnectionResetError) as e:
            raise RuntimeError("crowd-world worker process exited unexpectedly (killed? out of memory?)") from e
        if status != "ok":
            raise RuntimeError(f"crowd-world worker failed:\n{value}")
        return value

    # ------------------------------------------------------------------ per shard
    def send(self, k: int, method: str, *args: Any) -> None:
        """Start ``Shard.method(*args)`` on shard ``k`` (runs at once, to completion, for the local shard)."""
        conn = self.conns[k]
        if conn is None:
            self._local_result = getattr(self.local, method)(*args)
            return
        try:
            conn.send((method, args))
        except (BrokenPipeError, ConnectionResetError) as e:
            raise RuntimeError("crowd-world worker process exited unexpectedly (killed? out of memory?)") from e

    def wait(self, k: int) -> Any:
        """The result of the call last sent to shard ``k``."""
        conn = self.conns[k]
        if conn is None:
            out, self._local_result = self._local_result, None
            return out
        return self._recv(conn)

    def send_act_step(self, k: int, noise: np.ndarray, steps: np.ndarray, rho: float | None) -> None:
        """Start :meth:`Shard.act_step` on shard ``k`` (its slice of the ``noise`` and of ``steps``)."""
        self.send(k, "act_step", noise, steps, rho)

    # ------------------------------------------------------------------ whole batch
    def call(self, method: str, per_shard_args: list[tuple]) -> list[Any]:
        """``Shard.method`` on every shard, in parallel; results in shard order."""
        order = sorted(range(len(self.slices)), key=lambda k: self.conns[k] is None)  # workers first
        for k in order:
            self.send(k, method, *per_shard_args[k])
        return [self.wait(k) for k in range(len(self.slices))]

    def step(self, actions: np.ndarray, steps: np.ndarray, rho: float | None) -> StepOut:
        """Every world: ``actions`` ``(B, 2)``, step counters ``(B,)`` → the concatenated :class:`StepOut`."""
        return concat(self.call("step", [(actions[s], steps[s], rho) for s in self.slices]))

    def reset_all(self, rho: float | None) -> StepOut:
        return concat(self.call("reset_all", [(rho,)] * len(self.slices)))

    def get_streams(self) -> list[dict]:
        return [s for part in self.call("get_streams", [()] * len(self.slices)) for s in part]

    def set_streams(self, states: list[dict]) -> None:
        self.call("set_streams", [(states[s],) for s in self.slices])

    def close(self) -> None:
        """Stop the worker processes (idempotent)."""
        for c in getattr(self, "conns", []):
            if c is None:
                continue
            try:
                c.send(("close", None))
                c.close()
            except (OSError, BrokenPipeError):
                pass
        for p in getattr(self, "procs", []):
            p.join(timeout=5)
            if p.is_alive():
                p.terminate()
        self.conns, self.procs = [], []

    def __del__(self) -> None:
        self.close()


def concat(parts: list[StepOut]) -> StepOut:
    """Shards' :class:`StepOut` joined along the world axis."""
    return StepOut(*(np.concatenate([getattr(p, f) for p in parts]) for f in ("reward", "terminated", "truncated",
                                                                             "outcome")),
                   {k: np.concatenate([p.obs[k] for p in parts]) for k in parts[0].obs},
                   np.concatenate([p.steps for p in parts]))
