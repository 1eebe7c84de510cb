"""``crowdbench.bench``: the throughput benchmark under its public name — the very module
:mod:`crowdbench.cli.bench` (one object: what is set on one is set on the other)."""

import sys

from crowdbench.cli import bench as _bench

sys.modules[__name__] = _bench
