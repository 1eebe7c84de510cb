"""Issue 15's ordering at equal env steps: DS-RNN stopped at AIG-GST's shipped budget (5.85 M env steps, 1,016 PPO
iterations of 5,760 steps) against the shipped AIG-GST seeds, at the issue's bar cell (circle crossing, N = 20,
ρ = 0.5, 500 episodes) on three evaluation seeds.

The shipped DS-RNN seeds train 28.3 M env steps (22.3 M on H²INT's PPO schedule with σ fixed at 0.3, then 6.0 M at
σ = 0.15); the shipped AIG-GST seeds 5.85 M on the original recipe, because an AIG-GST env step costs ~5× a DS-RNN one
on a CPU. Both took about three hours of one core. This study asks which ordering holds when the env steps are equal,
on each DS-RNN recipe:

* ``dsrnn-stage1-5.85M-seed{0,1,2}``: the shipped DS-RNN's stage-1 recipe, a new run stopped at 1,016 iterations::

    crowdbench train dsrnn --seed S --learning-rate 3e-4 --schedule adaptive --epochs 4 --mini-batches 4
        --model learn_std=false --model action_std=0.3 --out runs/eq/dsrnn-s1-seedS --iterations 1016
        --minutes 150 --env-processes 1 --threads 1

* ``dsrnn-original-5.85M-seed0``: the original recipe — AIG-GST's — resumed from the committed 3.23 M state::

    crowdbench train dsrnn --resume studies/crowdbench-0.2/checkpoints/in-progress/dsrnn-small-seed0.pt
        --out runs/eq/dsrnn-orig-seed0 --iterations 1016 --minutes 200 --env-processes 1 --threads 1

* ``aig_gst[-seedK]``: the shipped AIG-GST checkpoints (5.85 M env steps each).

Each DS-RNN run's ``last.pt`` is committed as ``studies/crowdbench-0.2/checkpoints/equal-budget/<label>.pt`` (with its
``-history.json`` and ``-curve.png``).

Each cell is ``crowdbench evaluate METHOD --checkpoint CKPT --humans 20 --responsiveness 0.5 --episodes 500 --seed S
--worlds 100 --json FILE``; the script runs the ones whose FILE is missing and reuses the rest (delete them to
re-evaluate).

Usage: ``python studies/crowdbench-0.2/scripts/equal_budget_study.py [--checkpoints DIR] [--cache runs/eq]
[--out studies/crowdbench-0.2/equal-budget-15.json]``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

EVAL_SEEDS = (0, 1000, 2000)
CELL = ["--humans", "20", "--responsiveness", "0.5", "--episodes", "500", "--worlds", "100"]
STAGE1 = ("crowdbench train dsrnn --seed {s} --learning-rate 3e-4 --schedule adaptive --epochs 4 --mini-batches 4 "
          "--model learn_std=false --model action_std=0.3 --out runs/eq/dsrnn-s1-seed{s} --iterations 1016 "
          "--minutes 150 --env-processes 1 --threads 1")
ORIGINAL = ("crowdbench train dsrnn --resume studies/crowdbench-0.2/checkpoints/in-progress/dsrnn-small-seed0.pt "
            "--out runs/eq/dsrnn-orig-seed0 --iterations 1016 --minutes 200 --env-processes 1 --threads 1")
AIG = "crowdbench train aig_gst --variant small --seed {s} --env-processes 1 --threads 1 (resumed to 1,016 iterations)"


def entries(checkpoints: Path, cache: Path) -> list[dict[str, Any]]:
    """Label, method, checkpoint (path or shipped name), training command and evaluation-file stem of each entry."""
    out = [{"label": f"dsrnn-stage1-5.85M-seed{s}", "method": "dsrnn",
            "checkpoint": str(checkpoints / f"dsrnn-stage1-5.85M-seed{s}.pt"), "training": STAGE1.format(s=s),
            "stem": str(cache / f"dsrnn-s1-seed{s}-bar")} for s in (0, 1, 2)]
    out.append({"label": "dsrnn-original-5.85M-seed0", "method": "dsrnn",
                "checkpoint": str(checkpoints / "dsrnn-original-5.85M-seed0.pt"), "training": ORIGINAL,
                "stem": str(cache / "dsrnn-orig-seed0-bar")})
    for s, name in ((0, "aig_gst"), (1, "aig_gst-seed1"), (2, "aig_gst-seed2")):
        out.append({"label": name, "method": "aig_gst", "checkpoint": name, "training": AIG.format(s=s),
                    "stem": str(cache / f"{name}-bar")})
    return out


def cell(entry: dict[str, Any], seed: int) -> dict[str, Any]:
    """The bar cell's summary for one evaluation seed, evaluated unless its JSON exists."""
    path = Path(f"{entry['stem']}-{seed}.json")
    if not path.exists():
        cmd = ["crowdbench", "evaluate", entry["method"], "--checkpoint", entry["checkpoint"], *CELL,
               "--seed", str(seed), "--json", str(path)]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, env={**os.environ, "OMP_NUM_THREADS": "1"})
    s = json.loads(path.read_text())["summary"]
    keep = ("success_rate", "collision_rate", "timeout_rate", "nav_time")
    return {**{k: s[k] for k in keep}, "success_ci": s["ci"]["success_rate"]}


def checkpoint_steps(entry: dict[str, Any]) -> dict[str, Any]:
    """Iteration and env steps stored in the entry's checkpoint."""
    from crowdbench import checkpoints

    ckpt = checkpoints.load(checkpoints.resolve(entry["method"], entry["checkpoint"]), entry["method"])
    return {"iteration": ckpt.get("iteration"), "env_steps": ckpt.get("env_steps")}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--checkpoints", default="studies/crowdbench-0.2/checkpoints/equal-budget",
                    help="folder of the DS-RNN checkpoints (each run's last.pt, renamed)")
    ap.add_argument("--cache", default="runs/eq", help="folder of the evaluation files (made when missing)")
    ap.add_argument("--out", default="studies/crowdbench-0.2/equal-budget-15.json")
    args = ap.parse_args(argv)
    from crowdbench.io import write_text

    results = {}
    for e in entries(Path(args.checkpoints), Path(args.cache)):
        cells = {str(s): cell(e, s) for s in EVAL_SEEDS}
        mean = sum(c["success_rate"] for c in cells.values()) / len(cells)
        results[e["label"]] = {"training": e["training"], **checkpoint_steps(e), "bar_cell": cells,
                               "mean_success": round(mean, 4)}
        print(f"{e['label']:>28}: " + " / ".join(f"{100 * c['success_rate']:.1f}" for c in cells.values())
              + f" %  (mean {100 * mean:.1f} %)", file=sys.stderr)
    doc = {"what": __doc__.split("\n\n")[0].replace("\n", " "),
           "command": "python studies/crowdbench-0.2/scripts/equal_budget_study.py; each cell: "
                      "crowdbench evaluate METHOD --checkpoint CKPT "
                      + " ".join(CELL) + " --seed S --json FILE",
           "results": results}
    write_text(args.out, json.dumps(doc, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
