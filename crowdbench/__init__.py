"""crowdbench: a fast, faithful benchmark for robot navigation in dense crowds."""

from __future__ import annotations

__version__ = "0.1.0"
