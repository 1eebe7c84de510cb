"""The paper's responsiveness annealing (§Training Strategy), driven by finished episodes' outcomes."""

from __future__ import annotations

from collections import deque
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np


@dataclass
class Curriculum:
    """Responsiveness annealing (§Training Strategy): start at ``rho_init``; whenever the success rate over the last
    ``window`` episodes — all finished at the current ρ — is ≥ ``eta`` and ``cooldown`` episodes have finished since
    the last change, ρ ← max(ρ − ``delta``, ``rho_min``). ``enabled=False`` keeps ρ fixed (``--no-anneal``)."""

    rho_init: float = 0.8
    rho_min: float = 0.0
    delta: float = 0.1
    eta: float = 0.9
    window: int = 200
    cooldown: int = 200
    enabled: bool = True

    def __post_init__(self) -> None:
        self.rho = self.rho_init
        self.recent: deque[bool] = deque(maxlen=self.window)
        self.since_change = 0
        self.changes: list[tuple[int, float]] = []

    def record(self, successes: np.ndarray, episodes_total: int) -> bool:
        """Add finished episodes' outcomes (``episodes_total`` counts them too); returns True when ρ was lowered.
        Outcomes are taken one at a time, in order, so the schedule does not depend on how they are batched."""
        first = episodes_total - len(successes)
        lowered = False
        for i, s in enumerate(successes):
            self.recent.append(bool(s))
            self.since_change += 1
            if (self.enabled and self.rho > self.rho_min + 1e-9 and len(self.recent) == self.window
                    and self.since_change >= self.cooldown and sum(self.recent) >= self.eta * self.window):
                self.rho = round(max(self.rho - self.delta, self.rho_min), 10)
                self.recent.clear()
                self.since_change = 0
                self.changes.append((first + i + 1, self.rho))
                lowered = True
        return lowered

    def state_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d.update(rho=self.rho, recent=list(self.recent), since_change=self.since_change,
                 changes=[list(c) for c in self.changes])
        return d

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.rho, self.since_change = float(d["rho"]), int(d["since_change"])
        self.recent = deque((bool(x) for x in d["recent"]), maxlen=self.window)
        self.changes = [(int(a), float(b)) for a, b in d["changes"]]
