"""The paper's crowd: ORCA pedestrians whose response to the robot is latent and heterogeneous (§Environment Modeling).

Per episode, pedestrian i draws a responsiveness ρᵢ ~ U(max(0, ρ − δ), min(1, ρ + δ)) around the crowd mean ρ.
Per step, Iᵢ = 1 when the robot is inside pedestrian i's field of view (``fov`` about its heading) and within
``sensing_range``; a candidate cᵢ ~ Bernoulli(ρᵢ·Iᵢ) is drawn, and the latent state ξᵢ switches to cᵢ only after
``debounce`` (K) consecutive candidates disagree with it; at an episode's first step ξᵢ is initialised to the first
candidate (there is nothing to debounce against yet). With ξᵢ = 1 the robot (position and velocity) is in
pedestrian i's ORCA neighbour set; with ξᵢ = 0 it is replaced by a dummy outside the interaction range, i.e. left out.
Other pedestrians are always neighbours.

Consequences worth knowing: by the paper's formula ρ = 0 with the default δ = 0.2 still draws ρᵢ ∈ [0, 0.2] — a
few pedestrians respond now and then; with δ = 0, ρ = 0 reproduces ORCA with the robot absent exactly; ρ = 1 (δ = 0)
with a 360° field of view and a sensing range ≥ ``neighbor_dist`` reproduces ORCA with a visible robot exactly.
With K = 1 the long-run
share of responsive steps is E[ρᵢ·Iᵢ]; with K > 1 and constant visibility it is the debounced chain's stationary
share E₁/(E₀ + E₁), where E₀ = (1 − pᴷ)/((1 − p)·pᴷ) and E₁ is the same with p ↔ 1 − p (p = ρᵢ): 1/2 at p = 1/2,
0.89 at p = 0.7, K = 3 — debouncing makes the crowd's responses persistent, as intended.

ρᵢ, Iᵢ and ξᵢ never reach the robot's observation; :meth:`ResponsiveORCA.info` exposes them for analysis.
Change the crowd mean for all worlds between episodes with :meth:`ResponsiveORCA.set_responsiveness` (the training
curriculum lowers it); it takes effect at each world's next reset.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numba as nb
import numpy as np

from crowdbench.humans.base import CrowdState, register
from crowdbench.humans.orca import ORCABase


@register("responsive_orca")
class ResponsiveORCA(ORCABase):
    """Latent-responsive ORCA.

    Args:
        responsiveness: Crowd mean ρ ∈ [0, 1].
        spread: δ, half-width of the per-pedestrian draw around ρ.
        fov: Field of view about the heading [rad] (default π = 180°).
        sensing_range: Pedestrians notice the robot only within this centre distance [m].
        debounce: K, consecutive disagreeing candidates needed to flip ξ.
        **orca: :class:`~crowdbench.humans.orca.ORCAParams` fields.
    """

    BLOCK = 64
    """Steps of Bernoulli uniforms drawn at once per world (one generator call per world per BLOCK steps)."""

    def __init__(self, responsiveness: float = 0.5, spread: float = 0.2, fov: float = math.pi,
                 sensing_range: float = 5.0, debounce: int = 3, **orca) -> None:
        super().__init__(**orca)
        self.set_responsiveness(responsiveness)
        if not 0.0 <= spread <= 1.0:
            raise ValueError(f"spread must be in [0, 1], got {spread}")
        if not 0.0 < fov <= 2 * math.pi:
            raise ValueError(f"fov must be in (0, 2π] rad, got {fov}")
        if debounce < 1:
            raise ValueError(f"debounce must be ≥ 1, got {debounce}")
        self.spread, self.fov, self.sensing_range, self.debounce = spread, fov, sensing_range, int(debounce)

    def set_responsiveness(self, rho: float) -> None:
        """Set the crowd mean ρ used from each world's next episode on."""
        if not 0.0 <= rho <= 1.0:
            raise ValueError(f"responsiveness must be in [0, 1], got {rho}")
        self.responsiveness = float(rho)

    def bind(self, num_worlds: int, num_humans: int, obstacles, time_step: float) -> None:
        super().bind(num_worlds, num_humans, obstacles, time_step)
        shape = (num_worlds, num_humans)
        self.rho_i = np.zeros(shape)
        self.visible = np.zeros(shape, dtype=bool)
        self.xi = np.zeros(shape, dtype=bool)
        self._streak = np.zeros(shape, dtype=np.int64)
        self._fresh = np.ones(num_worlds, dtype=bool)
        # uniforms for the Bernoulli candidates, pre-drawn per world in blocks of BLOCK steps
        self._u = np.zeros((num_worlds, self.BLOCK, num_humans))
        self._cursor = np.full(num_worlds, self.BLOCK, dtype=np.int64)

    def reset(self, worlds: np.ndarray, rngs: Sequence[np.random.Generator], state: CrowdState) -> None:
        super().reset(worlds, rngs, state)
        lo = max(0.0, self.responsiveness - self.spread)
        hi = min(1.0, self.responsiveness + self.spread)
        for b in worlds:
            self.rho_i[b] = rngs[b].uniform(lo, hi, self.num_humans)
        self.xi[worlds] = False
        self.visible[worlds] = False
        self._streak[worlds] = 0
        self._fresh[worlds] = True
        self._cursor[worlds] = self.BLOCK

    def robot_in_view(self, state: CrowdState) -> np.ndarray:
        """Iᵢ ``(B, H)``: robot within ``sensing_range`` and inside the field of view about each heading."""
        rel = state.robot_position[:, None, :] - state.positions
        dist = np.sqrt(rel[..., 0] ** 2 + rel[..., 1] ** 2)
        ang = np.arctan2(rel[..., 1], rel[..., 0]) - state.headings
        off = np.abs((ang + np.pi) % (2 * np.pi) - np.pi)
        in_view = (off <= 0.5 * self.fov + 1e-12) if self.fov < 2 * math.pi else np.ones_like(off, dtype=bool)
        return in_view & (dist <= self.sensing_range) & state.active & state.robot_visible

    def robot_ignored(self, state: CrowdState, rngs: Sequence[np.random.Generator]) -> np.ndarray:
        """Advance the latent states one step (one compiled call, :func:`_latent_step`; :meth:`robot_in_view` and
        :func:`latent_step_reference` are its numpy statement) and return ``(B, H)``: ξᵢ = 0 or robot invisible."""
        for b in np.flatnonzero(self._cursor >= self.BLOCK):
            self._u[b] = rngs[b].random((self.BLOCK, self.num_humans))
            self._cursor[b] = 0
        ignored = np.empty(self.xi.shape, dtype=bool)
        _latent_step(state.robot_position, state.positions, state.headings, state.active, bool(state.robot_visible),
                     self.fov, self.sensing_range, self._u, self._cursor, self.rho_i, self.xi, self._streak,
                     self._fresh, self.debounce, self.visible, ignored)
        return ignored

    def info(self) -> dict[str, np.ndarray]:
        return {"rho_i": self.rho_i.copy(), "robot_in_view": self.visible.copy(), "xi": self.xi.copy()}


def latent_step_reference(model: ResponsiveORCA, state: CrowdState, u: np.ndarray) -> np.ndarray:
    """Numpy statement of one latent step (the test oracle of :func:`_latent_step`), in place on ``model``'s
    ``visible``, ``xi``, ``_streak``, ``_fresh``; ``u`` ``(B, H)`` are this step's uniforms. Returns ``ignored``."""
    model.visible = model.robot_in_view(state)
    candidate = u < model.rho_i * model.visible
    disagree = candidate != model.xi
    model._streak = np.where(disagree, model._streak + 1, 0)
    flip = (model._streak >= model.debounce) | model._fresh[:, None]
    model.xi = np.where(flip, candidate, model.xi)
    model._streak[flip] = 0
    model._fresh[:] = False
    return ~model.xi | (not state.robot_visible)


@nb.njit(cache=True)
def _latent_step(robot_pos, positions, headings, active, robot_visible, fov, sensing_range, u, cursor, rho_i, xi,
                 streak, fresh, debounce, visible, ignored):  # pragma: no cover - numba
    """One step of every pedestrian's latent state, in place (see the module docstring): visibility Iᵢ,
    candidate cᵢ ~ Bernoulli(ρᵢ·Iᵢ) from the pre-drawn uniforms ``u[b, cursor[b]]``, debounced switch of ξᵢ.

    The view angle comes from libm's ``atan2``, which may differ from numpy's ``arctan2`` in the last bit; only
    the comparison with the field of view uses it, so Iᵢ agrees with :meth:`ResponsiveORCA.robot_in_view` except
    within ~1e-16 rad of the field's edge.
    """
    B, H = xi.shape
    full = fov >= 2 * math.pi
    half = 0.5 * fov + 1e-12
    two_pi = 2 * np.pi
    for b in range(B):
        row = cursor[b]
        for h in range(H):
            rx, ry = robot_pos[b, 0] - positions[b, h, 0], robot_pos[b, 1] - positions[b, h, 1]
            dist = np.sqrt(rx * rx + ry * ry)
            in_view = True
            if not full:
                ang = math.atan2(ry, rx) - headings[b, h]
                in_view = abs((ang + np.pi) % two_pi - np.pi) <= half
            vis = in_view and dist <= sensing_range and active[b, h] and robot_visible
            visible[b, h] = vis
            cand = u[b, row, h] < (rho_i[b, h] if vis else 0.0)
            if cand != xi[b, h]:
                streak[b, h] += 1
            else:
                streak[b, h] = 0
            if streak[b, h] >= debounce or fresh[b]:
                xi[b, h] = cand
                streak[b, h] = 0
            ignored[b, h] = not xi[b, h] or not robot_visible
        cursor[b] = row + 1
        fresh[b] = False
