"""Social Force pedestrians, CrowdNav++'s variant (Helbing & Molnár 1995, simplified), vectorised over worlds.

    v ← v + dt · [ KI·(v_des − v) + Σⱼ A·exp((rᵢ + rⱼ − dᵢⱼ)/B)·n̂ⱼᵢ + Σ_w A_w·exp((rᵢ − d_iw)/B_w)·n̂_wi ],
    then clipped to v_pref,

with v_des the preferred velocity toward the goal (slowing to land on it, so there is no division by zero at the
goal), n̂ⱼᵢ the unit vector from neighbour j to pedestrian i, and the wall term pushing away from the nearest point of
every obstacle edge. The robot is a neighbour when it is visible (``robot_visible``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from crowdbench.humans.base import CrowdState, HumanModel, preferred_velocity, register


@register("social_force")
class SocialForce(HumanModel):
    """Args (CrowdNav++'s values): A [m/s²], B [m], KI [1/s]; wall_A [m/s²], wall_B [m] for obstacle repulsion."""

    def __init__(self, A: float = 2.0, B: float = 1.0, KI: float = 1.0, wall_A: float = 2.0, wall_B: float = 0.5):
        for name, v in (("A", A), ("B", B), ("KI", KI), ("wall_A", wall_A), ("wall_B", wall_B)):
            if not v >= 0 or (name in ("B", "wall_B") and v == 0):
                raise ValueError(f"{name} must be {'> 0' if name.endswith('B') else '≥ 0'}, got {v}")
        self.A, self.B, self.KI, self.wall_A, self.wall_B = A, B, KI, wall_A, wall_B

    def step(self, state: CrowdState, rngs: Sequence[np.random.Generator]) -> np.ndarray:
        p, v, r = state.positions, state.velocities, state.radii
        desired = preferred_velocity(p, state.goals, state.v_pref, state.time_step)
        acc = self.KI * (desired - v)
        # neighbours: other pedestrians (+ the robot when visible)
        others_p = np.concatenate([state.robot_position[:, None], p], 1)
        others_r = np.concatenate([state.robot_radius[:, None], r], 1)
        others_ok = np.concatenate([np.full((len(p), 1), state.robot_visible), state.active], 1)
        diff = p[:, :, None, :] - others_p[:, None, :, :]  # (B, H, H+1, 2): from neighbour to me
        dist = np.sqrt(diff[..., 0] ** 2 + diff[..., 1] ** 2)
        ok = others_ok[:, None, :] & state.active[:, :, None] & (dist > 1e-9)
        H = p.shape[1]
        ok[:, np.arange(H), np.arange(H) + 1] = False
        mag = np.where(ok, self.A * np.exp((r[:, :, None] + others_r[:, None, :] - dist) / self.B), 0.0)
        acc += ((mag / np.maximum(dist, 1e-9))[..., None] * diff).sum(axis=2)
        if len(state.edges):
            a, b = state.edges[:, 0], state.edges[:, 1]  # (S, 2)
            ab = b - a
            t = np.clip(np.einsum("bhsi,si->bhs", p[:, :, None] - a, ab) / np.einsum("si,si->s", ab, ab), 0, 1)
            away = p[:, :, None] - (a + t[..., None] * ab)  # (B, H, S, 2)
            dw = np.sqrt(away[..., 0] ** 2 + away[..., 1] ** 2)
            wmag = self.wall_A * np.exp((r[:, :, None] - dw) / self.wall_B) / np.maximum(dw, 1e-9)
            acc += (wmag[..., None] * away).sum(axis=2)
        new_v = v + state.time_step * acc
        speed = np.sqrt(new_v[..., 0] ** 2 + new_v[..., 1] ** 2)
        new_v *= np.minimum(1.0, state.v_pref / np.maximum(speed, 1e-12))[..., None]
        return np.where(state.active[..., None], new_v, 0.0)
