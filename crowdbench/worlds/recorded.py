"""The ETH/UCY scenes as worlds (layouts ``eth``, ``hotel``, ``univ``, ``zara1``, ``zara2``).

A recorded-scene layout holds its scene's test recordings (:mod:`crowdbench.datasets.ethucy`). The recordings carry
no map, so a scene has **no static obstacles** here and its walkable region is the box spanned by the recorded
positions; nothing stops a simulated pedestrian from leaving it, as nothing stopped the recorded ones.

* **Robot** (every model): it crosses the scene's busy area — the mean of all recorded positions, ``centre`` — along
  a uniformly random direction θ: start ``centre − L·u(θ)``, goal ``centre + L·u(θ)``, with ``L`` the largest
  half-length ≤ ``robot_half_length`` (6 m) keeping both ends inside the walkable box shrunk by 0.5 m; directions
  with ``L`` < 2.5 m, or ends within 0.1 m of an obstacle added through the config, are redrawn (bounded).
* **Pedestrians with the ``replay`` / ``reactive_replay`` models** are the recorded people of a 60 s window drawn per
  episode (:mod:`crowdbench.humans.replay`); ``num_humans`` is then the number of *slots* — a cap on how many recorded
  people can be present at once (a person who finds every slot taken is left out; :data:`PEAK` gives each scene's
  most at once, the value that leaves nobody out).
* **Pedestrians with any other model** (ORCA, Social Force, …) start at a recorded person's first position and walk
  to that person's last one (each coordinate ±0.5 m), placed without overlap; on arrival they take another recorded
  person's last position as their next goal.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from crowdbench.datasets.ethucy import SCENES, load_recording, tracks
from crowdbench.worlds.layouts import Layout

PEAK = {"eth": 27, "hotel": 18, "univ": 75, "zara1": 20, "zara2": 20}
"""Most recorded people present at once in each scene's test recordings."""


class RecordedScene(Layout):
    """One ETH/UCY scene (module docstring). Args: ``robot_half_length`` [m]."""

    scene: ClassVar[str] = ""
    separate_goals = False
    renew_uniforms = 1

    def __init__(self, robot_half_length: float = 6.0) -> None:
        if not robot_half_length > 0:
            raise ValueError(f"robot_half_length={robot_half_length!r}; valid choices: a length > 0 [m]")
        self.robot, self.robot_half_length = "scene", float(robot_half_length)
        self.recordings = {name: tracks(load_recording(name)) for name in SCENES[self.scene]}
        rows = np.concatenate([load_recording(n) for n in SCENES[self.scene]])
        self.lo, self.hi = rows[:, 2:4].min(axis=0), rows[:, 2:4].max(axis=0)
        self.centre = rows[:, 2:4].mean(axis=0)
        firsts, lasts = [], []
        for _, _, pos in self.recordings.values():
            seen = ~np.isnan(pos[..., 0])  # (T, P)
            p = np.flatnonzero(seen.any(axis=0))
            first = seen[:, p].argmax(axis=0)
            last = len(seen) - 1 - seen[::-1, p].argmax(axis=0)
            firsts.append(pos[first, p])
            lasts.append(pos[last, p])
        self.person_starts, self.person_ends = np.concatenate(firsts), np.concatenate(lasts)
        self.half_size = float(np.abs(np.concatenate([self.lo, self.hi])).max()) + 1.0

    def robot_endpoints(self, rng, edges, radius):
        from crowdbench.geometry import point_segment_distance

        lo, hi = self.lo + 0.5, self.hi - 0.5
        c = np.clip(self.centre, lo, hi)
        for _ in range(256):
            th = rng.uniform(0.0, 2 * math.pi)
            u = np.array([math.cos(th), math.sin(th)])
            limit = self.robot_half_length
            for k in range(2):  # both ends inside the box: |c_k ± L·u_k| within [lo_k, hi_k]
                if abs(u[k]) > 1e-12:
                    limit = min(limit, (hi[k] - c[k]) / abs(u[k]), (c[k] - lo[k]) / abs(u[k]))
            if limit < 2.5:
                continue
            ends = np.stack([c - limit * u, c + limit * u])
            if edges is not None and len(edges):  # clear of any extra obstacle, as every layout's robot
                d = point_segment_distance(ends[:, None], edges[None, :, 0], edges[None, :, 1])
                if (d <= radius + 0.1).any():
                    continue
            return ends[0], ends[1]
        raise ValueError(f"layout {self.name!r}: no robot crossing of ≥ 5 m fits the scene clear of the obstacles")

    def candidates(self, rng, index, n, m):
        k = rng.integers(0, len(self.person_starts), m)
        noise = rng.uniform(-0.5, 0.5, (2, m, 2))
        return self.person_starts[k] + noise[0], self.person_ends[k] + noise[1]

    def renew_goals(self, u, positions, goals):
        k = np.minimum((u[:, 0] * len(self.person_ends)).astype(np.int64), len(self.person_ends) - 1)
        return self.person_ends[k].copy()


def _scene(name: str) -> type[RecordedScene]:
    doc = f"The {name!r} ETH/UCY scene as a world (see :mod:`crowdbench.worlds.recorded`)."
    return type(f"{name.capitalize()}Scene", (RecordedScene,), {"scene": name, "name": name, "__doc__": doc,
                                                                "__module__": __name__})


EthScene, HotelScene, UnivScene, Zara1Scene, Zara2Scene = (_scene(s) for s in SCENES)
