"""How much of the success gap is the collision test? crowdbench (as CrowdNav) counts a collision when the robot's
disc touches a pedestrian's **at any time within the step** (swept); CrowdNav++ — whose scenario the paper's
observation and reward follow — checks the **positions at the start of each step** only (``calc_reward`` in
``crowd_sim_var_num.py`` runs before the agents move: a discrete test at the 0.25 s instants, so a contact that
begins and ends within one step is not a collision there).

Evaluation only (every policy trained with the swept test): the same 500 seeded episodes per cell with the world's
robot–pedestrian clearance taken at the end of each step instead of its minimum over the step. The world's step is
wrapped, not changed: the compiled ``motion`` and ``outcome`` kernels run as always, with ``d_min`` recomputed from
the moved positions between them.

Usage: ``python studies/crowdbench-0.2/scripts/collision_semantics.py [OUT.json]``
(default ``studies/crowdbench-0.2/collision-semantics.json``).
"""

from __future__ import annotations

import contextlib
import json
import sys

import numpy as np
import torch

import crowdbench.worlds.world as world_module
from crowdbench.evaluation import run_episodes, summarize
from crowdbench.io import write_text
from crowdbench.policies import make_policy
from crowdbench.worlds._kernels import motion, outcome

POLICIES = (("orca", {}), ("h2int", {}), ("h2int", {"checkpoint": "h2int-seed2"}), ("sarl", {}))
CELLS = ((20, 0.5), (20, 0.0), (30, 0.0))


def _advance_end_of_step(robot_vel, human_vel, pos, vel, v_pref, radius, active, edges, dt, iters, disp, clip_robot,
                         goal, heading, steps, prev_goal_dist, robot_turns, max_steps, rw, change_every, floats, ints,
                         flags, reached, change_due, mirror) -> int:
    """``crowdbench.worlds._kernels.advance`` with the robot–pedestrian clearance of the moved positions."""
    terms, reward, d_min, result, overlaps = floats[:5], floats[5], floats[6], ints[0], ints[1]
    robot_hit, terminated, truncated = flags[0], flags[1], flags[2]
    vel[:, 0] = robot_vel
    vel[:, 1:] = human_vel
    if not motion(pos, vel, v_pref, radius, active, edges, dt, iters, disp, robot_hit, d_min, clip_robot):
        return -1
    centre = np.linalg.norm(pos[:, 1:] - pos[:, :1], axis=-1)
    d_min[:] = np.where(active[:, 1:], centre - radius[:, 1:] - radius[:, :1], np.inf).min(axis=1, initial=np.inf)
    mirror[:, :pos.shape[1]] = pos
    return outcome(pos, vel, goal, radius, active, heading, steps, prev_goal_dist, d_min, robot_hit, robot_turns,
                   max_steps, rw, change_every, terms, reward, result, terminated, truncated, overlaps, reached,
                   change_due)


@contextlib.contextmanager
def end_of_step_collisions():
    swept = world_module.advance
    world_module.advance = _advance_end_of_step
    try:
        yield
    finally:
        world_module.advance = swept


def main(out: str = "studies/crowdbench-0.2/collision-semantics.json") -> None:
    torch.set_num_threads(1)
    rows = {}
    for name, kw in POLICIES:
        for humans, rho in CELLS:
            for test in ("swept", "end of step"):
                ctx = end_of_step_collisions() if test == "end of step" else contextlib.nullcontext()
                with ctx:
                    s = summarize(run_episodes(make_policy(name, **kw), 500, seed=0, num_worlds=100,
                                               num_humans=humans, human_model="responsive_orca",
                                               human_model_kwargs={"responsiveness": rho}))
                key = f"{name}{'-' + kw['checkpoint'] if kw else ''} | N={humans} rho={rho} | {test}"
                rows[key] = {k: s[k] for k in ("success_rate", "collision_rate", "timeout_rate", "nav_time")}
                print(key, rows[key], flush=True)
    write_text(out, json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main(*sys.argv[1:])
