"""Digests that say which crowd a result or a trained policy belongs to.

A stored leaderboard cell and a trained checkpoint are only comparable with others made on the same crowd: the
default world configuration, the layouts' settings, the pedestrian model's parameters and the rules in code that no
setting shows (bumped by hand in :data:`RULES`).
"""

from __future__ import annotations

import hashlib

RULES = "crowdnav++/1"
"""Version of the crowd rules that live in code rather than settings (placement, re-spawn, goal changes, sensing by
surface distance). Change it whenever such a rule changes: every stored cell and trained checkpoint then goes
stale."""


def crowd_digest(layouts: tuple[str, ...] = ("circle_crossing",), models: tuple[str, ...] = ("responsive_orca",)
                 ) -> str:
    """SHA-256 (16 hex digits) of :data:`RULES`, the default :class:`~crowdbench.config.WorldConfig`, the settings
    of ``layouts`` and the parameters of ``models``. With the defaults: the training crowd of every learned method
    (the digest it had before ``models`` took several names)."""
    from crowdbench.config import WorldConfig
    from crowdbench.humans import make as make_model
    from crowdbench.worlds.layouts import make_layout

    parts = [RULES, repr(WorldConfig())]
    for layout in sorted(set(layouts)):
        parts.append(f"{layout}: {sorted(vars(make_layout(layout)).items())}")
    for name in models:
        m = make_model(name)
        part = repr(getattr(m, "params", None)) + repr(sorted((k, v) for k, v in vars(m).items()
                                                            if isinstance(v, float)))
        if name != "responsive_orca":  # e.g. a learned crowd's weights (the training crowd's digest stays as it was)
            part = f"{name}: {part}{getattr(m, 'fingerprint', '')}"
        parts.append(part)
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]
