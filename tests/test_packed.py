"""The packed-token encoder (ragged attention, fused gate, oneDNN linear) computes the padded encoder's function."""

import pytest
import torch

from crowdbench.policies import fast_linear
from crowdbench.policies.fused_gate import _tanh, fused_gate
from crowdbench.policies.h2int_net import GRUGate, H2INTEncoder
from crowdbench.policies.packed import packed_encode


def _batch(B: int = 300, N: int = 20, seed: int = 0):
    g = torch.Generator().manual_seed(seed)
    robot = torch.randn(B, 9, generator=g)
    edges = torch.randn(B, N, 2, generator=g) * 3
    valid = torch.rand(B, N, generator=g) < torch.rand(B, 1, generator=g)  # 0..N visible, holes included
    valid[0] = False  # a robot that sees nobody
    return robot, edges, valid


@pytest.mark.parametrize("variant", ["h2int", "flat", "standard"])
def test_packed_encoder_matches_padded_forward_and_gradients(variant):
    torch.manual_seed(1)
    enc = H2INTEncoder(20, variant)
    robot, edges, valid = _batch()
    gz = torch.randn(robot.shape[0], 32)
    params = list(enc.parameters())
    z0 = enc(robot, edges, valid)
    g0 = torch.autograd.grad((z0 * gz).sum(), params)
    z1 = packed_encode(enc, robot, edges, valid)
    g1 = torch.autograd.grad((z1 * gz).sum(), params)
    assert torch.allclose(z0, z1, atol=2e-5)
    for a, b in zip(g0, g1, strict=True):
        assert torch.allclose(a, b, atol=1e-4 * max(1.0, a.abs().max().item())), (a - b).abs().max()


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


def test_fast_linear_matches_f_linear_with_gradients():
    x = torch.randn(777, 32, requires_grad=True)  # a row count that needs padding
    w, b = torch.randn(96, 32, requires_grad=True), torch.randn(96, requires_grad=True)
    y0, y1 = torch.nn.functional.linear(x, w, b), fast_linear.linear(x, w, b)
    assert torch.allclose(y0, y1, atol=1e-5)
    gy = torch.randn_like(y0)
    for a, c in zip(torch.autograd.grad((y0 * gy).sum(), [x, w, b]), torch.autograd.grad((y1 * gy).sum(), [x, w, b]),
                    strict=True):
        assert torch.allclose(a, c, atol=1e-3)


@pytest.mark.parametrize("variant", ["h2int", "flat", "standard"])
def test_fused_inference_kernel_matches_the_encoder(variant):
    """The one-kernel inference encoder (rollouts in the world processes) equals the encoder; trained-looking
    normaliser statistics, holes in the mask and a robot that sees nobody included."""
    from crowdbench.policies import fused_infer

    torch.manual_seed(3)
    enc = H2INTEncoder(20, variant)
    with torch.no_grad():
        enc.robot_norm._mean.normal_()
        enc.robot_norm._std.uniform_(0.5, 2.0)
        for p in enc.parameters():
            p.add_(torch.randn_like(p) * 0.1)  # away from the initial gate biases and layer-norm identities
    robot, edges, valid = _batch()
    assert fused_infer.supported(enc)
    with torch.no_grad():
        z0 = enc(robot, edges, valid)
        z1 = fused_infer.encode(enc, robot, edges, valid)
    assert torch.allclose(z0, z1, atol=1e-5), (z0 - z1).abs().max()
    with torch.no_grad():  # an optimiser step changes the weights in place: the kernel must see it
        enc.final_ln.bias.add_(1.0)
    assert torch.allclose(fused_infer.encode(enc, robot, edges, valid), z1 + 1.0, atol=1e-5)
    assert not fused_infer.supported(H2INTEncoder(20, "meanpool"))
