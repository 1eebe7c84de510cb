"""ORCA kernel throughput (agent-steps per second), one core, 64 worlds, agents on a circle crossing.

    python benchmarks/bench_orca.py [--quick]

Times :func:`crowdbench.humans.orca_kernel.orca_batch` alone (neighbour search, half-planes, linear programs)
while the crowd evolves (positions integrated between calls, outside the timing); the measurement is
:func:`crowdbench.bench.orca_agent_steps_per_s`, shared with ``crowdbench bench``. The like-for-like comparison with
the C++ RVO2 library (built ``-O2``, same crowd, same parameters, run in alternation) is
``benchmarks/bench_peers.py --orca-only --interleaved 5`` (README, "Speed").
"""

from __future__ import annotations

import argparse

from common import machine, pin_one_core

from crowdbench.bench import orca_agent_steps_per_s


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--quick", action="store_true")
    args = p.parse_args()
    pin_one_core()
    print(f"machine: {machine()}; pinned to 1 core")
    print(f"{'agents/world':>13} {'worlds':>7} {'agent-steps/s (median)':>24} {'spread':>12}")
    for n in (20, 50, 200):
        steps = (20 if args.quick else 120) if n < 200 else (5 if args.quick else 30)
        r = orca_agent_steps_per_s(n, 64, steps, repeats=5)
        print(f"{n:>13} {64:>7} {r['median']:>24,.0f} {r['spread']:>12,.0f}")


if __name__ == "__main__":
    main()
