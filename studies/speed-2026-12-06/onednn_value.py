"""SARL's look-ahead products through oneDNN (``torch.ops.mkldnn._linear_pointwise``, as
``crowdbench/policies/h2int/_kernels/fast_linear.py`` calls it) against the ``addmm`` the value network runs today:
bitwise equality and CPU milliseconds per product, one thread, alternated per layer.

    PYTHONPATH=. python studies/speed-2026-12-06/onednn_value.py [--rounds 3]

Layers (in → out) at the row counts of a paper-suite cell's look-ahead with 50 worlds × 81 actions: the per-pedestrian
layers on ``R`` rows (``mlp1`` 13 → 150 → 100, the score MLP's 100 → 100 halves, ``mlp2`` 100 → 50, the score's 100 →
1), the per-state layers on ``S`` = 4,050 rows (``mlp3`` 56 → 150 → 100 → 100), and one SGD batch's ``R`` ≈ 2,000.
"""

import argparse
import time

import torch

from crowdbench.policies.h2int._kernels.fast_linear import _lp

LAYERS = [(13, 150), (150, 100), (100, 100), (100, 50), (100, 1), (56, 150)]


def cpu_ms(f, n: int) -> float:
    f()
    t = time.process_time()
    for _ in range(n):
        f()
    return (time.process_time() - t) / n * 1e3


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    torch.set_num_threads(1)
    g = torch.Generator().manual_seed(0)
    print("| rows | layer | bitwise equal | addmm ms | oneDNN ms (per round) |\n|---:|---|---|---|---|")
    for rows in (2000, 4050, 24300, 48600):
        for i, o in LAYERS:
            x = torch.randn(rows, i, generator=g)
            w, b = torch.randn(o, i, generator=g) * 0.1, torch.randn(o, generator=g)
            eq = torch.equal(torch.addmm(b, x, w.t()), _lp(x, w, b))
            n = max(3, int(2e8 / (rows * i * o)))
            mkl = lambda x=x, w=w, b=b: torch.addmm(b, x, w.t())  # noqa: E731
            dnn = lambda x=x, w=w, b=b: _lp(x, w, b)  # noqa: E731
            pairs = [(cpu_ms(mkl, n), cpu_ms(dnn, n)) for _ in range(a.rounds)]
            print(f"| {rows} | {i} → {o} | {eq} | {' · '.join(f'{p[0]:.2f}' for p in pairs)} | "
                  f"{' · '.join(f'{p[1]:.2f}' for p in pairs)} |", flush=True)


if __name__ == "__main__":
    main()
