"""The ``predicted`` robot observation: AIG-GST's spatial edges (CrowdNav++ ``crowd_sim_pred*.py``).

``robot`` ``(9,)`` as ``relative``; ``humans`` ``(N_max, 2 + 2K)`` = for each pedestrian in sensing range, nearest
first, its position relative to the robot followed by its K predicted positions, each relative to the robot's
*current* position; ``mask`` ``(N_max,)``. The predictor reads the robot's :class:`~crowdbench.predictors.base.Track`
(positions seen over the last 5 steps), kept by this builder across calls — one builder per batch of worlds.

:meth:`PredictedObservation.reward` is AIG-GST's prediction-intrusion penalty on this observation: the minimum over
pedestrians in view and k = 1…K of ``1[‖p̂_k − p_robot‖ < intrusion_distance]·(−20 / 2^{k+1})`` (−5, −2.5, … at
k = 1, 2, …); training adds it to the paper's reward (:mod:`crowdbench.training.shards`).
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from crowdbench.config import WorldConfig
from crowdbench.predictors.base import Predictor, Track, make_predictor
from crowdbench.robots.observations import BOUND, Observation, _build, _robot_box, nearest_first

INTRUSION_PENALTY = -20.0
"""Scale of the intrusion penalty: step k costs ``INTRUSION_PENALTY / 2^{k+1}`` [-]."""


class PredictedObservation(Observation):
    """Current and predicted relative positions of the pedestrians in view (see the module docstring).

    Args:
        config: World configuration (sensing range, ``max_humans_observed``).
        predictor: Registry name (``gst``, ``const_vel``, ``truth``, or a plug-in) or a predictor instance.
        checkpoint: The ``gst`` predictor's checkpoint (path or shipped name; default: the shipped one).
        intrusion_distance: Radius of the intrusion penalty about the robot's centre [m] (CrowdNav++: 0.6).
    """

    name = "predicted"

    def __init__(self, config: WorldConfig, predictor: str | Predictor = "gst", checkpoint: str | None = None,
                 intrusion_distance: float = 0.6) -> None:
        super().__init__(config)
        kwargs = {"checkpoint": checkpoint} if checkpoint is not None else {}
        if checkpoint is not None and predictor != "gst":
            raise ValueError(f"checkpoint={checkpoint!r} is for predictor 'gst', not {predictor!r}")
        self.predictor = make_predictor(predictor, **kwargs)
        self.horizon = self.predictor.horizon
        if not intrusion_distance > 0:
            raise ValueError(f"intrusion_distance={intrusion_distance!r}; valid choices: a positive number [m]")
        self.intrusion_distance = float(intrusion_distance)
        self.track: Track | None = None

    def space(self) -> spaces.Dict:
        n = self.config.max_humans_observed
        return spaces.Dict({"robot": _robot_box(),
                            "humans": spaces.Box(-BOUND, BOUND, (n, 2 + 2 * self.horizon), np.float32),
                            "mask": spaces.Box(0.0, 1.0, (n,), np.float32)})

    def build(self, world) -> dict[str, np.ndarray]:
        n, H, B = self.config.max_humans_observed, world.num_humans, world.num_worlds
        obs = _build(world, 2, self.config.sensing_range, H, by_id=True)  # every slot: more people than n in view
        seen = obs["mask"] > 0.5
        if self.track is None or self.track.pos.shape[0] != B or self.track.pos.shape[2] != H:
            self.track = Track(B, H)
        self.track.update(world.pos[:, 1:], seen, world.steps)
        pred = self.predictor.predict(self.track, world) - world.pos[:, 0][:, None, None, :]  # (B, H, K, 2)
        feats = np.concatenate([obs["humans"], pred.reshape(B, H, -1)], axis=-1)
        humans, mask = nearest_first(obs["humans"], seen, feats, n)
        return {"robot": obs["robot"], "humans": humans, "mask": mask}

    def reward(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """The prediction-intrusion penalty ``(B,)`` of observations ``obs`` (see the module docstring) [-]."""
        B, n, _ = obs["humans"].shape
        pred = obs["humans"][..., 2:].reshape(B, n, self.horizon, 2)
        close = (np.hypot(pred[..., 0], pred[..., 1]) < self.intrusion_distance) & (obs["mask"][..., None] > 0.5)
        cost = INTRUSION_PENALTY / 2.0 ** (np.arange(1, self.horizon + 1) + 1)
        return np.where(close, cost, 0.0).min(axis=(1, 2))
