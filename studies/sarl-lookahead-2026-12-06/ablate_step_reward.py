"""How much of SARL's success comes from the step reward of its one-step look-ahead?

    PYTHONPATH=. python studies/sarl-lookahead-2026-12-06/ablate_step_reward.py [--episodes 300] [--seed 900000]

SARL acts greedily on ``Q(s, a) = r(s, a) + γ^{Δt·v_pref}·V(s′)`` over its 81 actions
(``crowdbench/policies/value/lookahead.py``, CrowdNav's ``multi_human_rl.py``): ``r`` is CrowdNav's reward of the
swept step against pedestrians moved at their estimated velocities — −0.25 for any action that touches one within
0.25 s —, ``V`` the trained network. Variant ``no-step-reward`` drops ``r`` (``Q = γ^{Δt·v_pref}·V(s′)``, the same
network and next states), leaving what the network learned. Both run SARL's shipped training seeds 0–2
through ``crowdbench evaluate`` (the board's evaluation path) at Table I Medium (circle crossing, N = 20,
ρ = 0.5) and Table II N = 30 (ρ = 0), on world seeds ``--seed`` + k — a range disjoint from the board's (0 + k),
its check range (100000 + k) and the out-of-sample runs (777000 + k). Prints success / collision / timeout [%].
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import tempfile

import torch

from crowdbench.cli import main as cli
from crowdbench.policies.value import lookahead as la

SETTINGS = {"I Medium": ("20", "0.5"), "II N=30": ("30", "0.0")}
CHECKPOINTS = ("sarl", "sarl-seed1", "sarl-seed2")


def evaluate(checkpoint: str, humans: str, rho: str, episodes: int, seed: int) -> dict:
    """``crowdbench evaluate sarl`` of a shipped checkpoint; its summary."""
    path = os.path.join(tempfile.mkdtemp(), "out.json")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        cli(["evaluate", "sarl", "--checkpoint", checkpoint, "--humans", humans, "--responsiveness", rho,
             "--seed", str(seed), "--episodes", str(episodes), "--json", path])
    with open(path) as f:
        return json.load(f)["summary"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=300)
    ap.add_argument("--seed", type=int, default=900000)
    args = ap.parse_args()
    torch.set_num_threads(1)
    shipped = la.lookahead

    def no_step_reward(*a, **k):
        nxt, r = shipped(*a, **k)
        return nxt, torch.zeros_like(r)

    print("| checkpoint | setting | as shipped: success / collision / timeout [%] | no step reward |")
    print("|---|---|---|---|")
    for ck in CHECKPOINTS:
        for name, (humans, rho) in SETTINGS.items():
            cells = []
            for fn in (shipped, no_step_reward):
                la.lookahead = fn
                try:
                    s = evaluate(ck, humans, rho, args.episodes, args.seed)
                finally:
                    la.lookahead = shipped
                lo, hi = s["ci"]["success_rate"]
                cells.append(f"{100 * s['success_rate']:.1f} [{100 * lo:.1f}, {100 * hi:.1f}] / "
                             f"{100 * s['collision_rate']:.1f} / {100 * s['timeout_rate']:.1f}")
            print(f"| {ck} | {name} | {cells[0]} | {cells[1]} |", flush=True)


if __name__ == "__main__":
    main()
