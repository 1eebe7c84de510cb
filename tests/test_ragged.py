"""Ragged attention's packed entry points (``[q | k | v]`` and ``[k | v]`` in one tensor) compute the three-tensor
form's numbers bit for bit — outputs and gradients — with and without autograd."""

import pytest
import torch

from crowdbench.nn.ragged import ragged_attention, ragged_attention_kv, ragged_attention_qkv, row_offsets


@pytest.mark.parametrize(("heads", "d"), [(4, 128), (8, 64), (4, 32)])
@pytest.mark.parametrize("robot_only", [False, True])
def test_packed_forms_equal_the_three_tensor_form_bit_for_bit(heads, d, robot_only):
    g = torch.Generator().manual_seed(heads * d + robot_only)
    counts = torch.randint(0, 15, (60,), generator=g)
    counts[0] = 0  # a sample with no tokens
    off = row_offsets(counts)
    T, B = int(off[-1]), len(counts)
    qkv = torch.randn(T, 3 * d, generator=g, requires_grad=True)
    q_robot = torch.randn(B, d, generator=g, requires_grad=True)
    gout = torch.randn(B if robot_only else T, d, generator=g)
    inputs = [qkv, q_robot] if robot_only else [qkv]
    q = q_robot if robot_only else qkv[:, :d]
    ref = ragged_attention(q, qkv[:, d:2 * d], qkv[:, 2 * d:], off, robot_only, heads)
    ref_grads = torch.autograd.grad((ref * gout).sum(), inputs)
    if robot_only:
        out = ragged_attention_kv(q_robot, qkv[:, d:], off, True, heads)
    else:
        out = ragged_attention_qkv(qkv, off, heads)
    grads = torch.autograd.grad((out * gout).sum(), inputs)
    assert torch.equal(out, ref)
    assert all(torch.equal(a, b) for a, b in zip(grads, ref_grads, strict=True))
    assert ref_grads[0].abs().sum() > 0  # the gradients reach every block
    with torch.no_grad():
        plain = (ragged_attention_kv(q_robot, qkv[:, d:], off, True, heads) if robot_only
                 else ragged_attention_qkv(qkv, off, heads))
    assert torch.equal(plain, ref)
