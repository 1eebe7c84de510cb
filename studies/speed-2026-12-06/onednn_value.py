"""SARL's look-ahead products (or, with ``--model gst``, the GST predictor's) through oneDNN
(``torch.ops.mkldnn._linear_pointwise``, as ``crowdbench/policies/h2int/_kernels/fast_linear.py`` calls it) against
the ``addmm`` the networks run today: bitwise equality and CPU milliseconds per product, one thread, alternated per
layer.

    PYTHONPATH=. python studies/speed-2026-12-06/onednn_value.py [--rounds 3] [--model sarl|gst]

``sarl``: layers (in → out) at the row counts of a paper-suite cell's look-ahead with 50 worlds × 81 actions: the
per-pedestrian layers on ``R`` rows (``mlp1`` 13 → 150 → 100, the score MLP's 100 → 100 halves, ``mlp2`` 100 → 50,
the score's 100 → 1), the per-state layers on ``S`` = 4,050 rows (``mlp3`` 56 → 150 → 100 → 100), and one SGD
batch's ``R`` ≈ 2,000. ``gst``: AIG-GST's predictor (``crowdbench/predictors/gst.py``: embedding 4 → 64, attention
64 → 192 and 64 → 64, feed-forward 64 → 128 → 64, LSTM gates 64 → 256, head 64 → 5) on the pedestrians of 1,024 to
7,680 packed rows (a rollout step of 192 worlds has ≈ 3,840), then CPU nanoseconds per element of ``tanh`` and
``sigmoid`` on an LSTM state ``(rows, 64)``.
"""

import argparse
import time

import torch

from crowdbench.policies.h2int._kernels.fast_linear import _lp

MODELS = {"sarl": ((2000, 4050, 24300, 48600), [(13, 150), (150, 100), (100, 100), (100, 50), (100, 1), (56, 150)]),
          "gst": ((1024, 3840, 7680), [(4, 64), (64, 256), (64, 192), (64, 64), (64, 128), (128, 64), (64, 5)])}


def cpu_ms(f, n: int) -> float:
    f()
    t = time.process_time()
    for _ in range(n):
        f()
    return (time.process_time() - t) / n * 1e3


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--model", choices=sorted(MODELS), default="sarl")
    a = ap.parse_args()
    row_counts, layers = MODELS[a.model]
    torch.set_num_threads(1)
    g = torch.Generator().manual_seed(0)
    print("| rows | layer | bitwise equal | addmm ms | oneDNN ms (per round) |\n|---:|---|---|---|---|")
    for rows in row_counts:
        for i, o in layers:
            x = torch.randn(rows, i, generator=g)
            w, b = torch.randn(o, i, generator=g) * 0.1, torch.randn(o, generator=g)
            eq = torch.equal(torch.addmm(b, x, w.t()), _lp(x, w, b))
            n = max(3, int(2e8 / (rows * i * o)))
            mkl = lambda x=x, w=w, b=b: torch.addmm(b, x, w.t())  # noqa: E731
            dnn = lambda x=x, w=w, b=b: _lp(x, w, b)  # noqa: E731
            pairs = [(cpu_ms(mkl, n), cpu_ms(dnn, n)) for _ in range(a.rounds)]
            print(f"| {rows} | {i} → {o} | {eq} | {' · '.join(f'{p[0]:.2f}' for p in pairs)} | "
                  f"{' · '.join(f'{p[1]:.2f}' for p in pairs)} |", flush=True)
    if a.model == "gst":
        print("\n| rows | tanh ns/element | sigmoid ns/element (per round) |\n|---:|---|---|")
        for rows in row_counts:
            x = torch.randn(rows, 64, generator=g)
            per = 1e6 / x.numel()  # ms per call → ns per element
            pairs = [(cpu_ms(lambda: torch.tanh(x), 300) * per, cpu_ms(lambda: torch.sigmoid(x), 300) * per)  # noqa: B023
                     for _ in range(a.rounds)]
            print(f"| {rows} | {' · '.join(f'{p[0]:.2f}' for p in pairs)} | "
                  f"{' · '.join(f'{p[1]:.2f}' for p in pairs)} |", flush=True)


if __name__ == "__main__":
    main()
