"""Where an H²INT training iteration goes: rollout, PPO update, the encoder's share of the update, and the encoder's
cost per sample-pass — the quantities that decide ``train_steps_per_s`` (see README, Speed).

    python benchmarks/bench_update.py [--epochs 4] [--mini-batches 4] [--repeats 5]

Two cores as in training (2 world processes, 2 threads). After two warm-up iterations from scratch, each repeat
collects one rollout (8,192 transitions at the defaults) and runs one update on a copy of the same storage, then the
same update with the encoder replaced by a cheap stand-in (so the difference is the encoder's forward and backward).
Last, the encoder alone, forward + backward, on one mini-batch of that rollout with 1 and 2 threads. Medians and
spreads (max - min) over the repeats.
"""

from __future__ import annotations

import argparse
import copy
import statistics
import tempfile
import time

import torch
from common import machine

from crowdbench.training.rollout import collect
from crowdbench.training.train import TrainConfig, Trainer


def _stats(xs: list[float]) -> str:
    return f"{statistics.median(xs):8.3f} s  [{max(xs) - min(xs):.3f}]"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--epochs", type=int, default=TrainConfig.epochs)
    ap.add_argument("--mini-batches", type=int, default=TrainConfig.mini_batches)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    torch.set_num_threads(1)
    cfg = TrainConfig(epochs=args.epochs, mini_batches=args.mini_batches, eval_every=0, checkpoint_every=10**6)
    n = cfg.num_envs * cfg.steps_per_env
    with tempfile.TemporaryDirectory() as tmp:
        tr = Trainer(cfg, tmp, quiet=True)
        try:
            alg, env = tr.alg, tr.env
            tr.cfg.iterations = 2  # warm-up: numba compilation, TorchScript profiling runs
            tr.train()
            obs = env.get_observations()
            alg.train_mode()
            rollout, update, serial = [], [], []
            actor = alg.actor
            path = "packed_encode" if actor.packed else "bucketed"  # the encoder entry point training uses
            encoder = getattr(actor, path)

            def stub(r, e, v, max_groups=8, threads=None):  # noqa: ARG001 - a cheap stand-in with the encoder's output shape
                return actor.encoder.final_ln(actor.encoder.robot_mlp(r))
            for _ in range(args.repeats):
                t = time.perf_counter()
                with torch.inference_mode():
                    obs, _, _ = collect(alg, env, obs, cfg.steps_per_env, cfg.worker_acting)
                    alg.compute_returns(obs)
                rollout.append(time.perf_counter() - t)
                stored = copy.deepcopy(alg.storage)
                setattr(actor, path, stub)
                t = time.perf_counter()
                alg.update()
                serial.append(time.perf_counter() - t)
                setattr(actor, path, encoder)
                alg.storage = copy.deepcopy(stored)
                t = time.perf_counter()
                alg.update()
                update.append(time.perf_counter() - t)
            batch = n // cfg.mini_batches
            o = stored.observations.flatten(0, 1)[:batch]
            robot, edges, valid = o["robot"], o["humans"], o["mask"] > 0.5
            per_pass = {}
            for threads in (1, 2):
                alg.actor.threads = threads
                samples = []
                for k in range(args.repeats + 2):
                    t = time.perf_counter()
                    encoder(robot, edges, valid).square().sum().backward()
                    if k >= 2:
                        samples.append((time.perf_counter() - t) / batch * 1e6)
                per_pass[threads] = samples
            alg.actor.threads = cfg.threads
        finally:
            tr.close()
    print(f"# H²INT training iteration breakdown ({machine()})")
    print(f"schedule {cfg.epochs} epochs × {cfg.mini_batches} mini-batches, {n:,} transitions per iteration, "
          f"{cfg.threads} threads, {cfg.env_processes} world processes, encoder path: {path}")
    how = "world processes acting" if cfg.worker_acting else "pipelined"
    print(f"rollout ({how}, incl. returns)       {_stats(rollout)}")
    print(f"PPO update                           {_stats(update)}")
    print(f"  of which not the encoder           {_stats(serial)}")
    total = statistics.median(rollout) + statistics.median(update)
    print(f"iteration                            {total:8.3f} s  → {n / total:,.0f} env-steps/s (no evaluations)")
    for threads, xs in per_pass.items():
        print(f"encoder fwd+bwd, {batch:,}-sample mini-batch, {threads} thread(s): "
              f"{statistics.median(xs):6.1f} µs per sample-pass [{max(xs) - min(xs):.1f}]")
    need = (n / 5000 - statistics.median(rollout) - statistics.median(serial)) / (cfg.epochs * n) * 1e6
    print(f"for 5,000 env-steps/s the encoder would need ≤ {need:.1f} µs per sample-pass on 2 threads")


if __name__ == "__main__":
    main()
