"""Old code against new, in alternation: env steps per second of ``crowdbench train METHOD``'s loop (rollout + PPO
update, one thread, one world process; :func:`crowdbench.bench.train_steps_per_s`).

    git worktree add /tmp/old <commit>
    python benchmarks/ab_train.py --old /tmp/old --method aig_gst [--variant original] [--iterations 3] [--rounds 3]
                                  [--epochs 4 --mini-batches 4]

Each round runs the same measurement once with ``/tmp/old`` first on ``PYTHONPATH`` and once with this checkout, in
fresh processes (one thread, one world process, evaluations off), and prints both — env steps per second of
wall-clock and per second of the process's own CPU time, over ``--iterations`` iterations after two warm-up
iterations — and their ratios. The machine's speed drifts from minute to minute and other work shares its cores, so
only figures from the same round compare; on a busy machine the CPU-time figure is the steadier one.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

LOOP = r"""
import json, sys, tempfile, time, torch
torch.set_num_threads(1)
from crowdbench.training.config import TrainConfig
from crowdbench.training.methods import PPO_METHODS
from crowdbench.training.trainer import Trainer
method, iterations = sys.argv[1], int(sys.argv[2])
model = PPO_METHODS.get(method)().variant_model(sys.argv[3] if sys.argv[3] != "-" else None)
recipe = json.loads(sys.argv[4])
with tempfile.TemporaryDirectory() as tmp:
    cfg = TrainConfig.for_method(method, model=model, iterations=iterations + 2, eval_every=0,
                                 checkpoint_every=10**6, seed=0, threads=1, env_processes=1, **recipe)
    tr = Trainer(cfg, tmp, quiet=True)
    tr.train(stop_at=2)  # warm-up (numba compilation, allocator)
    steps0, wall, cpu = tr.env_steps, time.perf_counter(), time.process_time()
    tr.train()
    n = tr.env_steps - steps0
    print(json.dumps({"wall": n / (time.perf_counter() - wall), "cpu": n / (time.process_time() - cpu)}))
    tr.close()
"""


def measure(tree: Path, method: str, variant: str | None, iterations: int,
            recipe: dict[str, int] | None = None) -> dict[str, float]:
    """Env steps per second of wall-clock and of the process's CPU time, in one fresh process importing crowdbench
    from ``tree`` (``recipe``: PPO settings that replace the method's, e.g. ``{"epochs": 4}``)."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run([sys.executable, "-c", LOOP, method, str(iterations), variant or "-",
                          json.dumps(recipe or {})], env=env, cwd="/",
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", required=True, type=Path, help="checkout of the old code (git worktree)")
    ap.add_argument("--method", default="aig_gst")
    ap.add_argument("--variant", default=None)
    ap.add_argument("--iterations", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--epochs", type=int, default=None, help="PPO epochs per iteration (default: the method's)")
    ap.add_argument("--mini-batches", type=int, default=None, help="mini-batches per epoch (default: the method's)")
    args = ap.parse_args()
    recipe = {k: v for k, v in (("epochs", args.epochs), ("mini_batches", args.mini_batches)) if v is not None}
    new = Path(__file__).resolve().parent.parent
    print(f"{args.method} ({args.variant or 'default variant'}{''.join(f', {k} {v}' for k, v in recipe.items())}), "
          "env steps/s, one thread")
    for r in range(args.rounds):
        old_s = measure(args.old.resolve(), args.method, args.variant, args.iterations, recipe)
        new_s = measure(new, args.method, args.variant, args.iterations, recipe)
        print(" | ".join([f"round {r + 1}"] + [f"{k}: old {old_s[k]:6.0f}, new {new_s[k]:6.0f}, new / old "
                                                  f"{new_s[k] / old_s[k]:.2f}×" for k in ("wall", "cpu")]), flush=True)


if __name__ == "__main__":
    main()
