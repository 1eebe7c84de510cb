"""Does the pedestrians' attribute randomisation explain H²INT's gap to the paper? Success at N = 20 with the
calibrated scenario's randomised radius U(0.3, 0.5) m and speed U(0.5, 1.5) m/s switched off piece by piece, and
with the speeds capped at 1 m/s as CrowdNav++'s ORCA walks its pedestrians (calibration step 7, not adopted)
(evaluation only: the policies were trained with both randomised), 500 episodes per cell, evaluation seed 0.

Usage: ``python studies/crowdbench-0.2/scripts/attribute_study.py [OUT.json]``
(default ``studies/crowdbench-0.2/attribute-study.json``).
"""

from __future__ import annotations

import json
import sys

import torch

from crowdbench.evaluation import run_episodes, summarize
from crowdbench.io import write_text
from crowdbench.policies import make_policy

POLICIES = (("h2int", {}), ("h2int", {"checkpoint": "h2int-seed1"}), ("h2int", {"checkpoint": "h2int-seed2"}))
SETTINGS = (("default (r U(.3,.5), v U(.5,1.5))", {}),
            ("radius fixed 0.3", {"human_radius_range": None}),
            ("speed fixed 1.0", {"human_v_pref_range": None}),
            ("both fixed", {"human_radius_range": None, "human_v_pref_range": None}),
            ("speed capped 1.0 (CrowdNav++'s ORCA)", {"human_speed_cap": 1.0}))


def main(out: str = "studies/crowdbench-0.2/attribute-study.json") -> None:
    torch.set_num_threads(1)
    rows = {}
    for name, kw in POLICIES:
        for label, opts in SETTINGS:
            for rho in (0.5, 0.0):
                s = summarize(run_episodes(make_policy(name, **kw), 500, seed=0, num_worlds=50, num_humans=20,
                                           human_model="responsive_orca", human_model_kwargs={"responsiveness": rho},
                                           **opts))
                key = f"{name}{'-' + kw['checkpoint'] if kw else ''} | {label} | rho={rho}"
                rows[key] = {k: s[k] for k in ("success_rate", "collision_rate", "timeout_rate", "nav_time")}
                print(key, rows[key], flush=True)
    write_text(out, json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main(*sys.argv[1:])
