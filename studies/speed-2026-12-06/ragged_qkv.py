"""Ragged attention on a fused ``[q | k | v]`` projection: the three column slices passed to
``crowdbench.nn.ragged.ragged_attention`` (today: each sliced block copied contiguous, and autograd zero-fills a
full-width gradient for each and sums them) against one autograd function that takes the ``(T, 3d)`` tensor and
returns its gradient as the three blocks side by side (the same kernels, so the same bits: checked here).

    PYTHONPATH=. python studies/speed-2026-12-06/ragged_qkv.py [--rounds 3]

Shapes: AIG-GST's pedestrian self-attention at the ``small`` widths (d = 128, 4 heads) on one PPO mini-batch's
packed pedestrians (180 samples, 0–19 each); forward + backward of ``qkv = x Wᵀ`` → attention → sum, CPU ms per call.
"""

import argparse
import time

import numpy as np
import torch

from crowdbench.nn.ragged import _backward, _forward, ragged_attention, row_offsets


class Packed(torch.autograd.Function):
    """Attention on the blocks of ``qkv`` ``(T, 3d)``; one gradient for ``qkv``."""

    @staticmethod
    def forward(ctx, qkv, offsets, heads):
        d = qkv.shape[1] // 3
        a = qkv.detach().numpy()
        q, k, v = (np.ascontiguousarray(a[:, i * d:(i + 1) * d]) for i in range(3))
        sizes = np.diff(offsets)
        probs = np.empty(int(heads * (sizes * sizes).sum()), np.float32)
        out = np.empty_like(q)
        out[offsets[-1]:] = 0.0
        _forward(q, k, v, offsets, False, heads, probs, out)
        ctx.saved = (q, k, v, offsets, heads, probs)
        return torch.from_numpy(out)

    @staticmethod
    def backward(ctx, gout):
        q, k, v, offsets, heads, probs = ctx.saved
        g = [np.zeros_like(q), np.zeros_like(k), np.zeros_like(v)]
        _backward(q, k, v, offsets, False, heads, probs, gout.contiguous().numpy(), *g)
        return torch.from_numpy(np.concatenate(g, axis=1)), None, None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    torch.set_num_threads(1)
    g = torch.Generator().manual_seed(0)
    off = row_offsets(torch.randint(0, 20, (180,), generator=g))
    d, heads = 128, 4
    w = torch.randn(3 * d, d, generator=g, requires_grad=True)
    x = torch.randn(int(off[-1]), d, generator=g)

    def sliced():
        qkv = x @ w.t()
        ragged_attention(qkv[:, :d], qkv[:, d:2 * d], qkv[:, 2 * d:], off, False, heads).sum().backward()
        return w.grad

    def packed():
        Packed.apply(x @ w.t(), off, heads).sum().backward()
        return w.grad

    w.grad = None
    g1 = sliced().clone()
    w.grad = None
    print(f"{int(off[-1])} packed rows; weight gradients bitwise equal: {torch.equal(g1, packed())}")
    for r in range(a.rounds):
        times = []
        for f in (sliced, packed):
            f()
            t = time.process_time()
            for _ in range(100):
                w.grad = None
                f()
            times.append((time.process_time() - t) * 10)
        print(f"round {r + 1}: slices {times[0]:.2f} ms, packed {times[1]:.2f} ms, "
              f"packed / slices {times[1] / times[0]:.2f}")


if __name__ == "__main__":
    main()
