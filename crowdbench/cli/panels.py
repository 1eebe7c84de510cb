"""Trajectory panels (the paper's Fig. 4): one episode of a robot policy in each layout, drawn with matplotlib.

``crowdbench panels POLICY --out trajectories.png`` — the robot's path in red from its start (yellow disc) to its goal
(red star), every pedestrian's path dashed in its own colour, obstacles in black; the title of each panel gives the
outcome, time and path length. Reads the world only: it never changes what the simulation does.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from crowdbench.io import atomic_path

LAYOUTS = ("circle_crossing", "intersection", "split_flow", "random_wander")


def episode(policy: Any, layout: str, humans: int, seed: int, responsiveness: float) -> dict[str, Any]:
    """One episode of ``policy`` (world seed ``seed``): robot and pedestrian tracks ``(T + 1, A, 2)``, activity,
    the robot's goal, obstacles and outcome."""
    from crowdbench.config import make_config
    from crowdbench.robots.observations import make_observation
    from crowdbench.worlds import OUTCOMES, CrowdWorld

    cfg = make_config(num_humans=humans)
    world = CrowdWorld(cfg, 1, layout, "responsive_orca", {"responsiveness": responsiveness})
    world.reset(seeds=[seed])
    policy.reset()
    obs_builder = make_observation(policy.observation, cfg, **policy.observation_kwargs)
    track, active, goal = [world.pos[0].copy()], [world.active[0].copy()], world.goal[0, 0].copy()
    while True:
        res = world.step(policy.act(obs_builder.build(world)))
        track.append(world.pos[0].copy())
        active.append(world.active[0].copy())
        if res.terminated[0] or res.truncated[0]:
            break
    pos = np.asarray(track)
    return {"pos": pos, "active": np.asarray(active), "goal": goal, "edges": world.edges,
            "outcome": OUTCOMES[int(res.outcome[0])], "time": len(track[1:]) * world.dt,
            "path": float(np.linalg.norm(np.diff(pos[:, 0], axis=0), axis=-1).sum()),
            "half": world.layout.half_size}


def plot(policy_name: str, out: str, humans: int = 20, seed: int = 0, responsiveness: float = 0.5,
         checkpoint: str | None = None, layouts: tuple[str, ...] = LAYOUTS) -> str:
    """Draw one panel per layout into ``out`` (PNG, written atomically); returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crowdbench.policies import make_policy

    fig, axes = plt.subplots(1, len(layouts), figsize=(4.2 * len(layouts), 4.4), dpi=100)
    cmap = plt.get_cmap("tab20")
    for ax, layout in zip(np.atleast_1d(axes), layouts, strict=True):
        policy = make_policy(policy_name, **({"checkpoint": checkpoint} if checkpoint else {}))
        ep = episode(policy, layout, humans, seed, responsiveness)
        pos, act = ep["pos"], ep["active"]
        for a in range(1, pos.shape[1]):
            if not act[0, a]:
                continue
            seg = pos[:, a].copy()
            jumps = np.linalg.norm(np.diff(seg, axis=0), axis=-1) > 1.0  # re-spawned: do not draw the jump
            seg[1:][jumps] = np.nan
            ax.plot(seg[:, 0], seg[:, 1], "--", color=cmap(a % 20), linewidth=0.8, alpha=0.7)
        for e in ep["edges"]:
            ax.plot(e[:, 0], e[:, 1], "k-", linewidth=1.5)
        ax.plot(pos[:, 0, 0], pos[:, 0, 1], "-", color="red", linewidth=2.2, label="robot")
        ax.plot(*pos[0, 0], "o", color="gold", markersize=11, markeredgecolor="k", label="start")
        ax.plot(*ep["goal"], "*", color="red", markersize=15, markeredgecolor="k", label="goal")
        h = min(ep["half"], 11.0)
        ax.set(xlim=(-h, h), ylim=(-h, h), aspect="equal",
               title=f"{layout}\n{ep['outcome']}, {ep['time']:.1f} s, path {ep['path']:.1f} m")
        ax.grid(alpha=0.2)
    np.atleast_1d(axes)[0].legend(loc="lower left", fontsize=8)
    fig.suptitle(f"{policy_name}: N = {humans}, ρ = {responsiveness}, episode seed {seed}")
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with atomic_path(out, suffix=".png") as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    return out
