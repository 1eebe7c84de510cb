"""What bfloat16 autocast (AMX / AVX-512 BF16 on CPUs that have them) would buy the networks whose arithmetic bounds
crowdbench's slowest runs — measured, not adopted: it changes results (a greedy argmax over rounded values, PPO in
mixed precision), so it becomes a switch only with a trained result behind it.

    python benchmarks/bench_bf16.py [--rounds 2]

Prints the median milliseconds per call, float32 against bfloat16 in alternation, for: SARL's look-ahead forward
(81 actions × 20 pedestrians × 20 worlds), one SARL SGD batch (100 states, 10–30 pedestrian slots) and AIG-GST's
original-width encoder forward + backward (2,048 samples, 0–15 pedestrians in view). One thread; pause other work on
the machine.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

import torch
from common import machine, time_it

from crowdbench.policies.aig.model import AIGConfig, build_actor
from crowdbench.policies.value.model import build_net


def timed(fn: Callable[[bool], None], bf16: bool, repeats: int) -> float:
    """Median milliseconds per call of ``fn(bf16)`` over ``repeats`` calls, after one warm-up call."""
    fn(bf16)
    return time_it(lambda: fn(bf16), repeats=repeats)[0] * 1e3


def autocast(bf16: bool) -> torch.autocast:
    return torch.autocast("cpu", dtype=torch.bfloat16, enabled=bf16)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=2)
    args = p.parse_args()
    torch.set_num_threads(1)
    torch.manual_seed(0)

    sarl = build_net("sarl")
    rows = torch.randn(81 * 20, 20, 13), torch.ones(81 * 20, 20, dtype=torch.bool)

    def lookahead(bf16: bool) -> None:
        with torch.inference_mode(), autocast(bf16):
            sarl(*rows)

    opt = torch.optim.SGD(sarl.parameters(), lr=1e-3, momentum=0.9)
    state, target = torch.randn(100, 30, 13), torch.randn(100)
    mask = torch.arange(30)[None] < torch.randint(10, 31, (100, 1))

    def sgd(bf16: bool) -> None:
        with autocast(bf16):
            value = sarl(state, mask)
        loss = torch.nn.functional.mse_loss(value.float(), target)
        opt.zero_grad()
        loss.backward()
        opt.step()

    aig = build_actor(AIGConfig(), 30)
    seen = (torch.arange(30)[None] < torch.randint(0, 16, (2048, 1))).float()
    obs = {"robot": torch.randn(2048, 9), "humans": torch.randn(2048, 30, 12), "mask": seen}

    def encoder(bf16: bool) -> None:
        with autocast(bf16):
            z = aig.encode_samples(obs)
        z.float().square().mean().backward()

    print(machine())
    cases = (("SARL look-ahead forward, 32,400 rows", lookahead, 10), ("SARL SGD batch of 100", sgd, 100),
             ("AIG-GST encoder fwd+bwd, 2,048 samples", encoder, 3))
    for name, fn, repeats in cases:
        for r in range(args.rounds):
            fp32, bf16 = timed(fn, False, repeats), timed(fn, True, repeats)
            print(f"{name:40s} round {r}: float32 {fp32:8.1f} ms  bfloat16 {bf16:8.1f} ms  ({fp32 / bf16:.2f}×)")


if __name__ == "__main__":
    main()
