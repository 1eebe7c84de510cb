"""Where an H²INT training iteration goes: rollout, PPO update, the encoder's share of the update, and the encoder's
cost per sample-pass — the quantities that decide ``train_steps_per_s`` (see README, Speed).

    python benchmarks/bench_update.py [--epochs 4] [--mini-batches 4] [--repeats 5]

Two cores as in training (2 world processes that act and step, 2 threads in the update). After two warm-up
iterations from scratch, each repeat collects one rollout (8,192 transitions at the defaults) and runs one update on
a copy of the same storage, then the same update with the encoder replaced by a cheap stand-in (so the difference is
the encoder's forward and backward). Last, the packed encoder alone, forward + backward, on one mini-batch of that
rollout, one thread. Medians and spreads (max - min) over the repeats.
"""

from __future__ import annotations

import argparse
import copy
import statistics
import tempfile
import time

import torch
from common import machine

from crowdbench.training.config import TrainConfig
from crowdbench.training.rollout import PolicySnapshot, collect
from crowdbench.training.trainer import Trainer


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
            tr.train(stop_at=2)  # warm-up: numba compilation, allocator
            obs = env.get_observations()
            alg.train_mode()
            rollout, update, serial = [], [], []
            actor = alg.actor
            enc = actor.encoder

            def stub(o):  # a cheap stand-in with the encoder's output shape
                return enc.final_ln(enc.robot_mlp(o["robot"]))

            for _ in range(args.repeats):
                t = time.perf_counter()
                with torch.inference_mode():
                    obs, _, _ = collect(alg, env, obs, cfg.steps_per_env, PolicySnapshot.of(alg, tr.build))
                    alg.compute_returns(obs)
                rollout.append(time.perf_counter() - t)
                stored = copy.deepcopy(alg.storage)
                actor.encode_samples = stub
                t = time.perf_counter()
                alg.update()
                serial.append(time.perf_counter() - t)
                del actor.encode_samples
                alg.storage = copy.deepcopy(stored)
                t = time.perf_counter()
                alg.update()
                update.append(time.perf_counter() - t)
            batch = n // cfg.mini_batches
            o = stored.observations.flatten(0, 1)[:batch]
            robot, edges, valid = o["robot"], o["humans"], o["mask"] > 0.5
            per_pass = []
            for k in range(args.repeats + 2):
                t = time.perf_counter()
                enc.packed(robot, edges, valid).square().sum().backward()
                if k >= 2:
                    per_pass.append((time.perf_counter() - t) / batch * 1e6)
        finally:
            tr.close()
    print(f"# H²INT training iteration breakdown ({machine()})")
    print(f"schedule {cfg.epochs} epochs × {cfg.mini_batches} mini-batches, {n:,} transitions per iteration, "
          f"{cfg.threads} threads, {cfg.env_processes} world processes")
    print(f"rollout (world processes acting, incl. returns) {_stats(rollout)}")
    print(f"PPO update                           {_stats(update)}")
    print(f"  of which not the encoder           {_stats(serial)}")
    total = statistics.median(rollout) + statistics.median(update)
    print(f"iteration                            {total:8.3f} s  → {n / total:,.0f} env-steps/s (no evaluations)")
    print(f"packed encoder fwd+bwd, {batch:,}-sample mini-batch, 1 thread: "
          f"{statistics.median(per_pass):6.1f} µs per sample-pass [{max(per_pass) - min(per_pass):.1f}]")


if __name__ == "__main__":
    main()
