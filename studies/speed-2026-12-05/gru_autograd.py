"""A hand-written GRU sequence (one autograd Function: forward and backward loops over time) against ``nn.GRU``:
equal outputs and gradients in float64, then forward + backward CPU time at AIG-GST's update shapes.

    python studies/speed-2026-12-05/gru_autograd.py [--steps 30 --batch 8 --inputs 128 --hidden 64]
"""

from __future__ import annotations

import argparse
import time

import torch


class GRUSequence(torch.autograd.Function):
    """``nn.GRU``'s one-layer recurrence over ``x`` ``(T, B, I)`` from ``h0`` ``(1, B, H)`` → ``(T, B, H)``."""

    @staticmethod
    def forward(ctx, x, h0, w_ih, w_hh, b_ih, b_hh):
        steps, batch, _ = x.shape
        hidden = h0.shape[-1]
        gi = torch.addmm(b_ih, x.reshape(steps * batch, -1), w_ih.t()).view(steps, batch, 3 * hidden)
        h = h0[0]
        hs = x.new_empty(steps, batch, hidden)
        saved = x.new_empty(steps, batch, 4 * hidden)  # r, z, n, the hidden part of n's gate
        for t in range(steps):
            gh = torch.addmm(b_hh, h, w_hh.t())
            ir, iz, i_n = gi[t].chunk(3, 1)
            hr, hz, hn = gh.chunk(3, 1)
            r, z = torch.sigmoid(ir + hr), torch.sigmoid(iz + hz)
            n = torch.tanh(i_n + r * hn)
            h = n + z * (h - n)
            hs[t] = h
            saved[t] = torch.cat([r, z, n, hn], 1)
        ctx.save_for_backward(x, h0, w_ih, w_hh, hs, saved)
        return hs

    @staticmethod
    def backward(ctx, grad):
        x, h0, w_ih, w_hh, hs, saved = ctx.saved_tensors
        steps, batch, _ = x.shape
        hidden = h0.shape[-1]
        dgi, dgh = x.new_empty(steps, batch, 3 * hidden), x.new_empty(steps, batch, 3 * hidden)
        dh = torch.zeros_like(h0[0])
        for t in range(steps - 1, -1, -1):
            dh = dh + grad[t]
            r, z, n, hn = saved[t].chunk(4, 1)
            prev = hs[t - 1] if t else h0[0]
            dn = dh * (1 - z) * (1 - n * n)
            dz = dh * (prev - n) * z * (1 - z)
            dr = dn * hn * r * (1 - r)
            dgi[t] = torch.cat([dr, dz, dn], 1)
            dgh[t] = torch.cat([dr, dz, dn * r], 1)
            dh = dh * z + dgh[t] @ w_hh
        prev_all = torch.cat([h0, hs[:-1]], 0).reshape(steps * batch, hidden)
        gi_flat, gh_flat = dgi.reshape(steps * batch, -1), dgh.reshape(steps * batch, -1)
        return ((gi_flat @ w_ih).view_as(x), dh.unsqueeze(0), gi_flat.t() @ x.reshape(steps * batch, -1),
                gh_flat.t() @ prev_all, dgi.sum((0, 1)), dgh.sum((0, 1)))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=30)
    p.add_argument("--batch", type=int, default=8)
    p.add_argument("--inputs", type=int, default=128)
    p.add_argument("--hidden", type=int, default=64)
    a = p.parse_args()
    torch.set_num_threads(1)
    gru = torch.nn.GRU(a.inputs, a.hidden)
    x = torch.randn(a.steps, a.batch, a.inputs, requires_grad=True)
    h0 = torch.randn(1, a.batch, a.hidden)
    params = (gru.weight_ih_l0, gru.weight_hh_l0, gru.bias_ih_l0, gru.bias_hh_l0)

    g64 = torch.nn.GRU(a.inputs, a.hidden).double()
    g64.load_state_dict({k: v.double() for k, v in gru.state_dict().items()})
    p64 = (g64.weight_ih_l0, g64.weight_hh_l0, g64.bias_ih_l0, g64.bias_hh_l0)
    xa, ha = x.detach().double().requires_grad_(), h0.double().requires_grad_()
    xb, hb = x.detach().double().requires_grad_(), h0.double().requires_grad_()
    out_a = g64(xa, ha)[0]
    out_b = GRUSequence.apply(xb, hb, *p64)
    seed = torch.randn_like(out_a)
    da = torch.autograd.grad(out_a, [xa, ha, *p64], seed)
    db = torch.autograd.grad(out_b, [xb, hb, *p64], seed)
    print(f"float64: max |output difference| {(out_a - out_b).abs().max().item():.1e}, gradients "
          + " ".join(f"{(u - v).abs().max().item():.1e}" for u, v in zip(da, db, strict=True)))
    for name, run in (("nn.GRU", lambda: gru(x, h0)[0]), ("hand-written", lambda: GRUSequence.apply(x, h0, *params))):
        for _ in range(3):
            t = time.process_time()
            for _ in range(50):
                run().sum().backward()
            ms = (time.process_time() - t) / 50 * 1e3
        print(f"{name}: {ms:.2f} ms forward + backward (CPU)")


if __name__ == "__main__":
    main()
