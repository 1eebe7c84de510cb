"""Seconds per RL episode of ``crowdbench train sarl --sensing velocities`` at ``--threads 1`` against ``--threads 2``.

    python studies/sarl-threads-2026-12-07/measure.py [--rounds 2] [--rl-episodes 120]

Each round trains a short run at each thread count, in alternation, in fresh processes (30 imitation episodes, 5
imitation epochs, then ``--rl-episodes`` RL episodes of the CrowdNav recipe; evaluations off) and reads the
run's ``history.json``: the wall-clock time of its RL episodes after the first 50, per episode. Run it with
nothing else on the machine: the figure is the wall-clock of one run alone on it.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path


def seconds_per_episode(threads: int, rl_episodes: int) -> float:
    """Wall-clock seconds per RL episode (after the first 50) of one short SARL run at ``threads``."""
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([str(Path(sys.executable).parent / "crowdbench"), "train", "sarl", "--sensing", "velocities",
                        "--il-episodes", "30", "--il-epochs", "5", "--rl-episodes", str(rl_episodes),
                        "--eval-every", "1000000", "--threads", str(threads), "--out", out],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        h = json.loads((Path(out) / "history.json").read_text())["history"]
        rl = [(e, t) for p, e, t in zip(h["phase"], h["episode"], h["time"], strict=True) if p == "rl"]
        (e0, t0), (e1, t1) = next((e, t) for e, t in rl if e >= 50), rl[-1]
        return (t1 - t0) / (e1 - e0)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--rl-episodes", type=int, default=120)
    args = p.parse_args()
    for r in range(args.rounds):
        one = seconds_per_episode(1, args.rl_episodes)
        two = seconds_per_episode(2, args.rl_episodes)
        print(f"round {r}: threads 1 {one:.3f} s/episode, threads 2 {two:.3f} s/episode, speed-up {one / two:.2f}x",
              flush=True)


if __name__ == "__main__":
    main()
