"""Does calling ``orca_advance`` through its compiled entry point, past numba's per-call type dispatch, lower the
one-world call floor (issue 46's one-world target at N ≤ 50)?

    PYTHONPATH=. python studies/speed-2026-12-06/advance_entry_point.py [--rounds 3]

numba's dispatcher types all 11 arguments of ``orca_advance`` on every call; the compiled version's entry point
(the private ``Dispatcher.overloads[signature].entry_point``) skips that. Prints µs per call (best of 3 blocks of
20,000 calls, ``perf_counter`` around the call only) of a compiled no-op with the same 11 arguments and of
``orca_advance`` on the lattice crowd of ``bench_orca_rvo2.py`` (N = 1, 20, 50), each through the dispatcher and
through the entry point, alternated in one process.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numba

from crowdbench.humans.orca_kernel import orca_advance

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "speed-2026-12-05"))
from call_floor import _noop11, noop_args, ours, per_call  # noqa: E402


def entry(kernel, *args):
    """The compiled entry point of ``kernel`` for the types of ``args``."""
    sig = tuple(numba.typeof(a) for a in args)
    if sig not in kernel.overloads:
        kernel.compile(sig)
    return kernel.overloads[sig].entry_point


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    arrs = noop_args()
    noop = entry(_noop11, *arrs, 0.25)
    for r in range(args.rounds):
        parts = [f"no-op {per_call(lambda: _noop11(*arrs, 0.25), 200_000, 3):.2f} · "
                 f"{per_call(lambda: noop(*arrs, 0.25), 200_000, 3):.2f}"]
        for n in (1, 20, 50):
            direct = ours(n, bind=lambda *a: entry(orca_advance, *a))
            parts.append(f"N = {n}: {per_call(ours(n), 20_000, 3, True):.2f} · {per_call(direct, 20_000, 3, True):.2f}")
        print(f"round {r + 1} (µs, dispatcher · entry point): " + " | ".join(parts), flush=True)


if __name__ == "__main__":
    main()
