"""CrowdNav's one-step look-ahead, batched: joint states, the 81 holonomic actions, constant-velocity propagation and
the swept-collision reward, for all worlds × actions × pedestrians at once (float32). :func:`lookahead` is the fast
path (the pedestrian rows in one compiled loop), :func:`lookahead_reference` the same arithmetic in plain torch, its
bitwise test oracle.

Conventions (CrowdNav ``multi_human_rl.py`` / ``cadrl.py`` at 20d6780):

* **Joint state** of the robot with pedestrian j, rotated so that x points from the robot to its goal, 13 values:
  robot [d_g, v_pref, θ, r, v_x, v_y] ‖ pedestrian [p_x, p_y, v_x, v_y, r, d, r + r_j] (pedestrian position
  relative to the robot; d = centre distance; θ = 0 for the holonomic robot).
* **Actions**: a stop plus 16 headings ``linspace(0, 2π, 16, endpoint=False)`` × 5 speeds
  (e^{(i+1)/5} − 1)/(e − 1)·v_pref, i = 0…4 — 81 world-frame velocities.
* **Action value** ``Q(s, a) = r(s, a) + γ^{Δt·v_pref}·V(s′)``: the robot moves by ``a·Δt``, every pedestrian keeps
  its velocity (CrowdNav's ``query_env = false`` path — its default ``query_env = true`` asks the simulator for the
  true next states, valid only when the robot is invisible; with responsive pedestrians it would leak their latent
  state), and ``r`` is CrowdNav's reward of the swept step (:data:`CROWDNAV_REWARD`).
* **Sensing**: only pedestrians whose centre is within ``sensing_range`` enter the state (the paper's 5 m, the range
  every method of the leaderboard sees); a state with none gets one dummy pedestrian at rest 15 m behind the robot,
  far from any interaction, as CrowdNav++ pads unseen slots with far-away dummies.
* **Free space** (``free_space=True``, off by default): a state in which nobody is sensed is valued analytically,
  :func:`free_space_value` — the discounted goal reward of driving straight there at v_pref — instead of by the
  network on the dummy. CrowdNav never meets such states (its robot sees every human). Tried against CADRL's
  timeouts; it did not help them (README, "Baselines CADRL and SARL").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

DUMMY_DISTANCE = 15.0
"""Distance of the dummy pedestrian behind the robot when none is sensed [m]."""


@dataclass(frozen=True)
class CrowdNavReward:
    """CrowdNav's reward (``configs/env.config``), used by its value methods for targets and look-ahead."""

    success: float = 1.0
    """Goal reached (robot centre within the goal tolerance) [-]."""
    collision: float = -0.25
    """The robot's disc touched a pedestrian's during the step (swept) [-]."""
    discomfort_dist: float = 0.2
    """Surface distance below which the discomfort penalty applies [m]."""
    discomfort_factor: float = 0.5
    """Penalty ``(d_min − discomfort_dist)·discomfort_factor·Δt`` [1/(m·s)]."""

    def of_step(self, success: np.ndarray, collision: np.ndarray, d_min: np.ndarray, dt: float) -> np.ndarray:
        """Reward ``(B,)`` of world steps from their outcome flags and swept surface clearance ``d_min`` [m]
        (collision first, then success, then discomfort, as CrowdNav)."""
        near = d_min < self.discomfort_dist
        disc = np.where(near, (d_min - self.discomfort_dist) * self.discomfort_factor * dt, 0.0)
        return np.where(collision, self.collision, np.where(success, self.success, disc))


CROWDNAV_REWARD = CrowdNavReward()


def action_set(speeds: int = 5, headings: int = 16) -> np.ndarray:
    """CrowdNav's holonomic actions for v_pref = 1: ``(1 + headings·speeds, 2)``, the stop first, then heading-major
    (``itertools.product(rotations, speeds)``) [m/s]."""
    mags = (np.exp((np.arange(speeds) + 1) / speeds) - 1) / (np.e - 1)
    rot = np.linspace(0, 2 * np.pi, headings, endpoint=False)
    acts = [(0.0, 0.0)] + [(m * math.cos(r), m * math.sin(r)) for r in rot for m in mags]
    return np.array(acts)


@dataclass
class Scene:
    """The robot-centred inputs of a batch of states (torch float32, leading dimension ``B``)."""

    pos: torch.Tensor
    """Robot position ``(B, 2)`` [m]."""
    vel: torch.Tensor
    """Robot velocity ``(B, 2)`` [m/s]."""
    goal: torch.Tensor
    """``(B, 2)`` [m]."""
    radius: torch.Tensor
    """``(B,)`` [m]."""
    v_pref: torch.Tensor
    """``(B,)`` [m/s]."""
    rel: torch.Tensor
    """Pedestrian positions relative to the robot ``(B, K, 2)`` [m] (the dummy where none is sensed)."""
    hvel: torch.Tensor
    """``(B, K, 2)`` [m/s]."""
    hrad: torch.Tensor
    """``(B, K)`` [m]."""
    mask: torch.Tensor
    """``(B, K)`` bool, valid slots first; at least one per row."""
    sensed: torch.Tensor
    """``(B, K)`` bool: ``mask`` without the dummies (what the reward considers)."""

    @classmethod
    def from_obs(cls, obs: dict[str, np.ndarray], sensing_range: float) -> Scene:
        """From a ``full_state`` observation (robot ``(B, 9)``, humans ``(B, N, 5)``, mask ``(B, N)``), keeping the
        pedestrians within ``sensing_range`` [m] (K = the batch's largest count)."""
        robot = torch.as_tensor(obs["robot"], dtype=torch.float32)
        humans = torch.as_tensor(obs["humans"], dtype=torch.float32)
        sensed = torch.as_tensor(obs["mask"]) > 0.5
        sensed &= humans[..., 0].square() + humans[..., 1].square() <= sensing_range**2
        k = max(int(sensed.sum(dim=1).max()) if sensed.numel() else 0, 1)
        humans, sensed = humans[:, :k].clone(), sensed[:, :k].clone()  # nearest first: the sensed are a prefix
        pos, goal = robot[:, 0:2], robot[:, 3:5]
        none = ~sensed.any(dim=1)
        if none.any():
            to_goal = goal[none] - pos[none]
            unit = to_goal / to_goal.norm(dim=-1, keepdim=True).clamp_min(1e-9)
            humans[none, 0] = 0.0
            humans[none, 0, 0:2] = -DUMMY_DISTANCE * unit
            humans[none, 0, 4] = robot[none, 2]
        mask = sensed.clone()
        mask[:, 0] = True
        return cls(pos, robot[:, 7:9], goal, robot[:, 2], robot[:, 5], humans[..., 0:2], humans[..., 2:4],
                   humans[..., 4], mask, sensed)


def joint_state(pos: torch.Tensor, vel: torch.Tensor, goal: torch.Tensor, radius: torch.Tensor,
                v_pref: torch.Tensor, rel: torch.Tensor, hvel: torch.Tensor, hrad: torch.Tensor) -> torch.Tensor:
    """Rotated joint states ``(..., K, 13)`` from robot tensors ``(..., 2)``/``(...)`` and pedestrian tensors
    ``(..., K, 2)``/``(..., K)`` (positions relative to the robot)."""
    d = goal - pos
    rot = torch.atan2(d[..., 1], d[..., 0])
    c, s = torch.cos(rot), torch.sin(rot)
    k = rel.shape[-2]

    def turn(v: torch.Tensor, c: torch.Tensor, s: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return v[..., 0] * c + v[..., 1] * s, v[..., 1] * c - v[..., 0] * s

    rvx, rvy = turn(vel, c, s)
    robot = torch.stack([d.norm(dim=-1), v_pref, torch.zeros_like(v_pref), radius, rvx, rvy], dim=-1)
    ch, sh = c.unsqueeze(-1), s.unsqueeze(-1)
    px, py = turn(rel, ch, sh)
    hvx, hvy = turn(hvel, ch, sh)
    r = radius.unsqueeze(-1).expand_as(hrad)
    human = torch.stack([px, py, hvx, hvy, hrad, rel.norm(dim=-1), r + hrad], dim=-1)
    return torch.cat([robot.unsqueeze(-2).expand(*robot.shape[:-1], k, 6), human], dim=-1)


def current_state(scene: Scene) -> torch.Tensor:
    """Joint states of the scenes as they are ``(B, K, 13)`` (what the replay memory stores)."""
    return joint_state(scene.pos, scene.vel, scene.goal, scene.radius, scene.v_pref, scene.rel, scene.hvel,
                       scene.hrad)


def lookahead(scene: Scene, actions: torch.Tensor, dt: float, goal_tolerance: float,
              reward: CrowdNavReward = CROWDNAV_REWARD) -> tuple[torch.Tensor, torch.Tensor]:
    """Propagate every scene under every action.

    Args:
        scene: ``B`` scenes with ``K`` pedestrian slots.
        actions: World-frame robot velocities for v_pref = 1, ``(M, 2)`` float32 (scaled by each robot's v_pref).
        dt: Step [s].
        goal_tolerance: Success radius about the goal [m].
        reward: The reward constants.

    Returns:
        Next joint states ``(B, M, K, 13)`` and the rewards of the moves ``(B, M)``, float32, bitwise equal to
        :func:`lookahead_reference`: the robot's next positions, their headings to the goal and goal distances in
        torch, the ``B·M·K`` pedestrian rows in one compiled loop (:mod:`crowdbench.policies.value._kernels`).
    """
    from crowdbench.policies.value._kernels import lookahead_rows

    a = actions.unsqueeze(0) * scene.v_pref.view(-1, 1, 1)  # (B, M, 2)
    d = scene.goal.unsqueeze(1) - (scene.pos.unsqueeze(1) + a * dt)
    rot = torch.atan2(d[..., 1], d[..., 0])
    B, M, K = a.shape[0], a.shape[1], scene.rel.shape[1]
    nxt, r = np.empty((B, M, K, 13), np.float32), np.empty((B, M), np.float32)
    f = np.float32
    lookahead_rows(a.numpy(), torch.cos(rot).numpy(), torch.sin(rot).numpy(), d.norm(dim=-1).numpy(),
                   scene.v_pref.numpy(), scene.radius.numpy(), scene.rel.numpy(), scene.hvel.numpy(),
                   scene.hrad.numpy(), scene.sensed.numpy(), f(dt), f(goal_tolerance), f(reward.collision),
                   f(reward.success), f(reward.discomfort_dist), f(reward.discomfort_factor), nxt, r)
    return torch.from_numpy(nxt), torch.from_numpy(r)


def lookahead_reference(scene: Scene, actions: torch.Tensor, dt: float, goal_tolerance: float,
                        reward: CrowdNavReward = CROWDNAV_REWARD) -> tuple[torch.Tensor, torch.Tensor]:
    """:func:`lookahead` in plain torch, operation by operation — the readable version and the test oracle of the
    compiled fast path (bitwise equal).

    Args:
        scene: ``B`` scenes with ``K`` pedestrian slots.
        actions: World-frame robot velocities for v_pref = 1, ``(M, 2)`` (scaled by each robot's v_pref).
        dt: Step [s].
        goal_tolerance: Success radius about the goal [m].
        reward: The reward constants.

    Returns:
        Next joint states ``(B, M, K, 13)`` and the rewards of the moves ``(B, M)``.
    """
    a = actions.unsqueeze(0) * scene.v_pref.view(-1, 1, 1)  # (B, M, 2)
    pos = scene.pos.unsqueeze(1) + a * dt
    drel = (scene.hvel.unsqueeze(1) - a.unsqueeze(2)) * dt  # (B, M, K, 2) relative displacement
    rel0 = scene.rel.unsqueeze(1)
    rel1 = rel0 + drel
    # closest approach of the relative motion during the step (swept, as the world's collision test)
    t = (-(rel0 * drel).sum(-1) / drel.square().sum(-1).clamp_min(1e-12)).clamp(0.0, 1.0)
    centre = (rel0 + t.unsqueeze(-1) * drel).norm(dim=-1)
    surface = centre - scene.hrad.unsqueeze(1) - scene.radius.view(-1, 1, 1)
    d_min = torch.where(scene.sensed.unsqueeze(1), surface, torch.inf).amin(dim=-1)  # (B, M)
    success = (scene.goal.unsqueeze(1) - pos).norm(dim=-1) <= goal_tolerance
    disc = torch.where(d_min < reward.discomfort_dist,
                       (d_min - reward.discomfort_dist) * reward.discomfort_factor * dt, 0.0)
    r = torch.where(d_min <= 0.0, reward.collision, torch.where(success, reward.success, disc))
    M = actions.shape[0]
    nxt = joint_state(pos, a, scene.goal.unsqueeze(1).expand(-1, M, -1), scene.radius.unsqueeze(1).expand(-1, M),
                      scene.v_pref.unsqueeze(1).expand(-1, M), rel1, scene.hvel.unsqueeze(1).expand_as(rel1),
                      scene.hrad.unsqueeze(1).expand(-1, M, -1))
    return nxt, r


def free_space_value(goal_distance: torch.Tensor, v_pref: torch.Tensor, dt: float, gamma: float,
                     goal_tolerance: float) -> torch.Tensor:
    """Value of a state with nobody sensed: ``γ̄^{max(d_g − tolerance, 0)/(v_pref·Δt)}`` with γ̄ = γ^{Δt·v_pref} —
    the success reward (1) discounted by the steps of a straight drive at v_pref. Shapes broadcast; [-]."""
    steps = (goal_distance - goal_tolerance).clamp_min(0.0) / (v_pref * dt)
    return torch.pow(torch.tensor(gamma, dtype=goal_distance.dtype), dt * v_pref * steps)


def action_values(net: torch.nn.Module, scene: Scene, actions: torch.Tensor, dt: float, gamma: float,
                  goal_tolerance: float, free_space: bool = False) -> torch.Tensor:
    """``Q(s, a) = r + γ^{Δt·v_pref}·V(s′)`` for every scene and action ``(B, M)``: one network pass over all
    ``B·M`` next states (with ``free_space``, scenes with nobody sensed take :func:`free_space_value` instead)."""
    nxt, r = lookahead(scene, actions, dt, goal_tolerance)
    B, M, K, _ = nxt.shape
    mask = scene.mask.unsqueeze(1).expand(B, M, K).reshape(B * M, K)
    v = net(nxt.reshape(B * M, K, -1), mask).view(B, M)
    if free_space:
        free = ~scene.sensed.any(dim=1)
        if free.any():
            v_pref = scene.v_pref[free].unsqueeze(1)
            v[free] = free_space_value(nxt[free][:, :, 0, 0], v_pref, dt, gamma, goal_tolerance)
    return r + torch.pow(torch.tensor(gamma), dt * scene.v_pref).unsqueeze(1) * v
