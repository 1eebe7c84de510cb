"""A batch of crowd worlds split into shards stepped in parallel processes.

One shard is stepped in the calling process, every other one in a worker process (``multiprocessing``, fork where
the platform has it); a step sends each worker its slice of the actions, steps the local shard meanwhile, then
gathers. Worlds are independent and every episode's randomness comes from its own seed, so a sharded batch produces
exactly the same numbers as an unsharded one (tested) — sharding is a speed setting, not a modelling choice.

Workers build their worlds from the registries as seen at fork time; with the ``spawn`` start method (platforms
without fork) a pedestrian model registered at run time in ``__main__`` is not visible to them — register it through
the ``crowdbench.humans`` entry point instead.
"""

from __future__ import annotations

import multiprocessing as mp
import traceback
from dataclasses import dataclass
from multiprocessing.connection import Connection
from typing import Any

import numpy as np

from crowdbench.config import WorldConfig
from crowdbench.robots.observations import make_observation
from crowdbench.worlds.world import CrowdWorld


@dataclass
class ShardSpec:
    """What a worker needs to build its shard."""

    config: WorldConfig
    num_worlds: int
    layout: str
    human_model: str
    human_model_kwargs: dict[str, Any]
    observation: str = "relative"


class Shard:
    """``num_worlds`` worlds and their robot-observation builder."""

    def __init__(self, spec: ShardSpec) -> None:
        self.world = CrowdWorld(spec.config, spec.num_worlds, spec.layout, spec.human_model,
                                spec.human_model_kwargs)
        self.obs_builder = make_observation(spec.observation, spec.config)

    def step(self, actions: np.ndarray, steps: np.ndarray) -> tuple[np.ndarray, ...]:
        """``actions`` ``(n, 2)``, episode step counters ``(n,)`` → reward, terminated, truncated, outcome ``(n,)``."""
        self.world.steps[:] = steps
        res = self.world.step(actions)
        return res.reward, res.terminated, res.truncated, res.outcome

    def reset(self, seeds: list[int], mask: np.ndarray | None, rho: float | None) -> None:
        """New episodes in the worlds ``mask`` (all if None) with these seeds; ``rho`` sets the crowd's mean
        responsiveness first (for models that have one)."""
        model = self.world.human_model
        if rho is not None and hasattr(model, "set_responsiveness"):
            model.set_responsiveness(rho)
        if seeds:
            self.world.reset(seeds=seeds, mask=mask)

    def observe(self) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """Robot observations and the episode step counters."""
        return self.obs_builder.build(self.world), self.world.steps.copy()

    def reset_observe(self, seeds: list[int], mask: np.ndarray | None,
                      rho: float | None) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """:meth:`reset` then :meth:`observe` (one round trip for a worker)."""
        self.reset(seeds, mask, rho)
        return self.observe()


def _worker(conn: Connection, spec: ShardSpec) -> None:
    try:
        shard = Shard(spec)
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
    """``num_worlds`` worlds in ``processes`` shards (contiguous slices; shard 0 in this process)."""

    def __init__(self, spec: ShardSpec, processes: int = 1) -> None:
        if not 1 <= processes <= spec.num_worlds:
            raise ValueError(f"processes={processes}; valid choices: 1 … num_worlds ({spec.num_worlds})")
        self.num_worlds = spec.num_worlds
        sizes = [len(a) for a in np.array_split(np.arange(spec.num_worlds), processes)]
        self.bounds = np.cumsum([0, *sizes])
        self.local = Shard(ShardSpec(**{**spec.__dict__, "num_worlds": sizes[0]}))
        methods = mp.get_all_start_methods()
        ctx = mp.get_context("fork" if "fork" in methods else "spawn")
        self.conns: list[Connection] = []
        self.procs: list[Any] = []
        for n in sizes[1:]:
            parent, child = ctx.Pipe()
            p = ctx.Process(target=_worker, args=(child, ShardSpec(**{**spec.__dict__, "num_worlds": n})),
                            daemon=True, name="crowdbench-shard")
            p.start()
            child.close()
            self.conns.append(parent)
            self.procs.append(p)
        for c in self.conns:
            self._recv(c)

    @property
    def world(self) -> CrowdWorld:
        """The local shard's worlds (all of them when ``processes == 1``)."""
        return self.local.world

    @staticmethod
    def _recv(conn: Connection) -> Any:
        status, value = conn.recv()
        if status != "ok":
            raise RuntimeError(f"crowd-world worker failed:\n{value}")
        return value

    def _slices(self) -> list[slice]:
        return [slice(int(a), int(b)) for a, b in zip(self.bounds[:-1], self.bounds[1:], strict=True)]

    def call(self, method: str, per_shard_args: list[tuple]) -> list[Any]:
        """Run ``Shard.method`` on every shard in parallel; results in shard order."""
        for conn, args in zip(self.conns, per_shard_args[1:], strict=True):
            conn.send((method, args))
        first = getattr(self.local, method)(*per_shard_args[0])
        return [first, *(self._recv(c) for c in self.conns)]

    def step(self, actions: np.ndarray, steps: np.ndarray) -> tuple[np.ndarray, ...]:
        """All worlds: ``actions`` ``(B, 2)``, step counters ``(B,)`` → reward, terminated, truncated, outcome."""
        parts = self.call("step", [(actions[s], steps[s]) for s in self._slices()])
        return tuple(np.concatenate(x) for x in zip(*parts, strict=True))

    def reset(self, seeds: list[int], mask: np.ndarray | None,
              rho: float | None) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """New episodes in the worlds ``mask`` (all if None), seeds in world order; returns :meth:`observe`."""
        args, used = [], 0
        for s in self._slices():
            m = None if mask is None else mask[s]
            k = (s.stop - s.start) if m is None else int(m.sum())
            args.append((seeds[used:used + k], m, rho))
            used += k
        return self._gather(self.call("reset_observe", args))

    def observe(self) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """Robot observations ``{group: (B, …)}`` and episode step counters ``(B,)``."""
        return self._gather(self.call("observe", [()] * len(self._slices())))

    @staticmethod
    def _gather(parts: list) -> tuple[dict[str, np.ndarray], np.ndarray]:
        obs = {k: np.concatenate([p[0][k] for p in parts]) for k in parts[0][0]}
        return obs, np.concatenate([p[1] for p in parts])

    def close(self) -> None:
        """Stop the worker processes (idempotent)."""
        for c in getattr(self, "conns", []):
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
