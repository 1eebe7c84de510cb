"""One robot's decision latency among 20 pedestrians, on one thread against every core, in alternation.

    python benchmarks/bench_decision.py [--policies sarl cadrl] [--rounds 3] [--repeats 5]

``crowdbench bench`` reports the same figures (``decision_ms`` and ``decision_ms_all_cores``) inside its full run;
this prints only them, round by round, for a quick check on a machine whose other work is paused. The decisions are
the same on any thread count for CADRL and SARL (bitwise, ``tests/test_bench_and_tables.py``).
"""

from __future__ import annotations

import argparse

from crowdbench.bench import all_cores, cpu_model, decision_ms


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--policies", nargs="+", default=["sarl", "cadrl"])
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--repeats", type=int, default=5, help="timings of 200 decisions per figure")
    a = p.parse_args()
    cores = all_cores()
    print(f"{cpu_model()}; {cores} cores; median ms per decision (N = 20, ρ = 0.5, circle crossing)")
    for r in range(a.rounds):
        for name in a.policies:
            one = decision_ms(name, a.repeats)["median"]
            every = decision_ms(name, a.repeats, threads=cores)["median"]
            print(f"round {r}  {name:8s} 1 thread {one:6.3f} ms   {cores} threads {every:6.3f} ms")


if __name__ == "__main__":
    main()
