"""Provenance: the software and the machine that computed a cell or wrote a board file (light: no torch)."""

from __future__ import annotations

import contextlib
import platform
from pathlib import Path
from typing import Any

PACKAGES = ("numpy", "torch", "pymunk", "numba", "pettingzoo", "gymnasium", "rsl-rl-lib")
"""The libraries whose versions :func:`provenance` records."""


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``; the platform's processor or architecture where there is none), e.g.
    ``"AMD EPYC 9V74 80-Core Processor"``: results that depend on the instruction set are traced by it."""
    cpu = platform.processor() or platform.machine()
    with contextlib.suppress(OSError, StopIteration), open("/proc/cpuinfo") as f:
        cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    return cpu



def provenance() -> dict[str, Any]:
    """Crowdbench version and commit, Python and package versions and CPU model of this run (the machine that wrote
    the file; each cell records the CPU it ran on, see :func:`run_cell`)."""
    import platform
    import subprocess
    from importlib import metadata

    from crowdbench import __version__

    root = Path(__file__).resolve().parents[2]
    commit = None
    if (root / ".git").exists():
        try:
            commit = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                                    timeout=10).stdout.strip() or None
        except (OSError, subprocess.SubprocessError):
            commit = None
    versions = {}
    for name in PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None

    return {"crowdbench": __version__, "commit": commit, "python": platform.python_version(), "cpu": cpu_model(),
            "packages": versions}
