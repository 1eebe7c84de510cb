"""How do learned robots collide? For each collision of an evaluation (circle crossing, N = 20, ρ = 0.5, the
calibrated scenario), the pedestrian it touched and the geometry of the contact: was that pedestrian responsive
(latent ξ = 1) just before, was the robot inside its field of view, the robot's speed, the angle between the robot's
velocity and the direction to the pedestrian (0° = driving into them, 180° = moving away), and both closing speeds
along that direction [m/s] (robot: its velocity towards the pedestrian; pedestrian: its velocity towards the robot).

A collision with the robot moving away (angle > 90°) while the pedestrian closes in is a rear-end contact: an
unresponsive pedestrian faster than the robot (the calibrated crowd walks at U(0.5, 1.5) m/s, the robot at most 1 m/s)
walking into it.

Usage: ``python studies/crowdbench-0.2/scripts/collision_study.py [OUT.json] [--episodes N]``
(default ``studies/crowdbench-0.2/collision-study.json``,
300 episodes per policy, world seeds 10,000 + k).
"""

from __future__ import annotations

import argparse
import json
import statistics

import numpy as np
import torch

from crowdbench.config import make_config
from crowdbench.humans.base import make as make_model
from crowdbench.io import write_text
from crowdbench.policies import make_policy
from crowdbench.robots.observations import make_observation
from crowdbench.worlds import CrowdWorld

POLICIES = (("h2int", {}), ("h2int-seed2", {"checkpoint": "h2int-seed2"}), ("sarl", {}))
WORLDS = 50


def collisions(policy_name: str, kwargs: dict, episodes: int, rho: float = 0.5) -> dict:
    """Outcome counts and one row per collision (see the module docstring)."""
    config = make_config(num_humans=20)
    policy_id = policy_name.split("-")[0]
    policy = make_policy(policy_id, config, **kwargs)
    model = make_model("responsive_orca", responsiveness=rho)
    world = CrowdWorld(config, WORLDS, "circle_crossing", model)
    builder = make_observation(policy.observation, config, **policy.observation_kwargs)
    outcomes = {"success": 0, "collision": 0, "timeout": 0}
    rows = []
    for batch in range(-(-episodes // WORLDS)):
        world.reset(seeds=[10_000 + batch * WORLDS + b for b in range(WORLDS)])
        policy.reset()
        running = np.ones(WORLDS, dtype=bool)
        running[episodes - batch * WORLDS:] = False
        while running.any():
            action = policy.act(builder.build(world))
            xi, in_view = model.xi.copy(), model.visible.copy()
            res = world.step(action)
            for b in np.flatnonzero(running & (res.terminated | res.truncated)):
                running[b] = False
                kind = {1: "success", 2: "collision", 3: "timeout"}[int(res.outcome[b])]
                outcomes[kind] += 1
                if kind != "collision":
                    continue
                rel = world.pos[b, 1:] - world.pos[b, 0]
                gap = np.linalg.norm(rel, axis=1) - world.radius[b, 1:] - world.radius[b, 0]
                gap[~world.active[b, 1:]] = np.inf
                h = int(np.argmin(gap))
                u = rel[h] / np.linalg.norm(rel[h])
                v_robot, v_ped = world.vel[b, 0], world.vel[b, h + 1]
                speed = float(np.linalg.norm(v_robot))
                angle = float(np.degrees(np.arccos(np.clip(v_robot @ u / max(speed, 1e-9), -1.0, 1.0))))
                rows.append({"time": float(world.steps[b] * world.dt), "responsive": bool(xi[b, h]),
                             "robot_in_view": bool(in_view[b, h]), "rho_i": float(model.rho_i[b, h]),
                             "robot_speed": speed, "angle_deg": angle, "robot_closing": float(v_robot @ u),
                             "pedestrian_closing": float(-(v_ped @ u)),
                             "pedestrian_v_pref": float(world.v_pref[b, h + 1])})
    rear = [r for r in rows if r["angle_deg"] > 90.0 and r["pedestrian_closing"] > 0.0]
    summary = {"episodes": episodes, "outcomes": outcomes, "collisions": len(rows),
               "rear_end": len(rear), "responsive": sum(r["responsive"] for r in rows),
               "robot_in_view": sum(r["robot_in_view"] for r in rows)}
    if rear:
        summary["rear_end_median_pedestrian_v_pref"] = statistics.median(r["pedestrian_v_pref"] for r in rear)
        summary["rear_end_median_pedestrian_closing"] = statistics.median(r["pedestrian_closing"] for r in rear)
    return {"summary": summary, "collisions": rows}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("out", nargs="?", default="studies/crowdbench-0.2/collision-study.json")
    p.add_argument("--episodes", type=int, default=300)
    args = p.parse_args()
    torch.set_num_threads(1)
    result = {}
    for label, kwargs in POLICIES:
        result[label] = collisions(label, kwargs, args.episodes)
        print(label, json.dumps(result[label]["summary"]))
    write_text(args.out, json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
