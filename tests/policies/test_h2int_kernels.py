"""The packed-token encoder (the fast path: ragged attention, segment mean, fused gate, oneDNN linear) computes the
eager reference encoder's function, forward and gradients, for every variant — with oneDNN and with its fallback."""

import pytest
import torch

from crowdbench.policies.h2int._kernels import fast_linear
from crowdbench.policies.h2int._kernels.fused_gate import _tanh, fused_gate
from crowdbench.policies.h2int.model import VARIANTS, GRUGate, H2INTEncoder


def _batch(B: int = 300, N: int = 20, seed: int = 0):
    g = torch.Generator().manual_seed(seed)
    robot = torch.randn(B, 9, generator=g)
    edges = torch.randn(B, N, 2, generator=g) * 3
    valid = torch.rand(B, N, generator=g) < torch.rand(B, 1, generator=g)  # 0..N visible, holes included
    valid[0] = False  # a robot that sees nobody
    return robot, edges, valid


def _trained_looking(enc: H2INTEncoder) -> H2INTEncoder:
    with torch.no_grad():
        enc.robot_norm._mean.normal_()
        enc.robot_norm._std.uniform_(0.5, 2.0)
        for p in enc.parameters():
            p.add_(torch.randn_like(p) * 0.1)  # away from the initial gate biases and layer-norm identities
    return enc


@pytest.mark.parametrize("onednn", [True, False])
@pytest.mark.parametrize("variant", VARIANTS)
def test_packed_encoder_matches_the_reference_forward_and_gradients(variant, onednn):
    torch.manual_seed(1)
    enc = _trained_looking(H2INTEncoder(20, variant))
    robot, edges, valid = _batch()
    gz = torch.randn(robot.shape[0], 32)
    params = list(enc.parameters())
    before = fast_linear.use_onednn(onednn)
    try:
        if not onednn:
            assert not fast_linear.onednn_active()  # the pure-PyTorch fallback is what runs
        z0 = enc(robot, edges, valid)
        g0 = torch.autograd.grad((z0 * gz).sum(), params)
        z1 = enc.packed(robot, edges, valid)
        g1 = torch.autograd.grad((z1 * gz).sum(), params, allow_unused=True)
    finally:
        fast_linear.use_onednn(before)
    assert torch.allclose(z0, z1, atol=2e-5), (z0 - z1).abs().max()
    for a, b in zip(g0, g1, strict=True):
        b = torch.zeros_like(a) if b is None else b  # e.g. the query weights of meanpool: unused by both
        assert torch.allclose(a, b, atol=1e-4 * max(1.0, a.abs().max().item())), (a - b).abs().max()
    with torch.inference_mode():  # inference (rollouts, evaluation) and one robot (decision latency)
        assert torch.allclose(enc.packed(robot, edges, valid), z0.detach(), atol=2e-5)
        assert torch.allclose(enc.packed(robot[:1], edges[:1], valid[:1]), z0[:1].detach(), atol=2e-5)
        assert torch.allclose(enc.packed(robot[5:6], edges[5:6], valid[5:6]), z0[5:6].detach(), atol=2e-5)


def test_fused_gate_matches_grugate():
    torch.manual_seed(2)
    gate = GRUGate(32)
    x, y = torch.randn(500, 32, requires_grad=True), torch.randn(500, 32, requires_grad=True)
    out0 = gate(x, y)
    out1 = fused_gate(gate, x, y)
    assert torch.allclose(out0, out1, atol=2e-6)
    go = torch.randn_like(out0)
    ins = [x, y, *gate.parameters()]
    for a, b in zip(torch.autograd.grad((out0 * go).sum(), ins), torch.autograd.grad((out1 * go).sum(), ins),
                    strict=True):
        assert torch.allclose(a, b, atol=5e-5)


def test_rational_tanh_is_within_4e7():
    xs = torch.linspace(-20, 20, 100_001)
    approx = torch.tensor([_tanh(float(v)) for v in xs[::97]])
    assert (approx - torch.tanh(xs[::97])).abs().max() < 4e-7


@pytest.mark.parametrize("onednn", [True, False])
def test_fast_linear_matches_f_linear_with_gradients(onednn):
    before = fast_linear.use_onednn(onednn)
    try:
        x = torch.randn(777, 32, requires_grad=True)  # a row count that needs padding
        w, b = torch.randn(96, 32, requires_grad=True), torch.randn(96, requires_grad=True)
        y0, y1 = torch.nn.functional.linear(x, w, b), fast_linear.linear(x, w, b)
        assert fast_linear.padded_rows(777) == (1024 if fast_linear.onednn_active() else 777)
        assert fast_linear.padded_rows(13) == 13  # small products never pad
    finally:
        fast_linear.use_onednn(before)
    assert torch.allclose(y0, y1, atol=1e-5)
    gy = torch.randn_like(y0)
    for a, c in zip(torch.autograd.grad((y0 * gy).sum(), [x, w, b]), torch.autograd.grad((y1 * gy).sum(), [x, w, b]),
                    strict=True):
        assert torch.allclose(a, c, atol=1e-3)


def test_onednn_is_forced_off_by_the_environment():
    import subprocess
    import sys

    code = ("from crowdbench.policies.h2int._kernels import fast_linear as f; "
            "print(f.onednn_active(), f.padded_rows(777))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={**__import__("os").environ, "CROWDBENCH_PURE_TORCH": "1"}).stdout.split()
    assert out == ["False", "777"]
