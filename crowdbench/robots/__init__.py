"""Robot sensing: observation builders (registry by name)."""

from __future__ import annotations

from crowdbench.robots.observations import (
    OBSERVATIONS,
    FullStateObservation,
    Observation,
    RelativeObservation,
    human_observation_space,
    human_observations,
    make_observation,
)

__all__ = ["OBSERVATIONS", "FullStateObservation", "Observation", "RelativeObservation", "human_observation_space",
           "human_observations", "make_observation"]
