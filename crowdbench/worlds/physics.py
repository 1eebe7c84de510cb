"""pymunk side of the world: one :class:`pymunk.Space` per world, agents as KINEMATIC circle bodies, obstacles as
static segments/polygons — the world's geometry store, kept equal to the numpy state in one C call per world.

The world's motion kernel integrates ``p ← p + v·dt`` itself — bit for bit what ``cpSpaceStep`` does to a kinematic
body (tested) — and :meth:`PymunkWorlds.sync` then moves the bodies. Measured on one world of 5 pedestrians
(``benchmarks/bench_pettingzoo.py``): stepping the spaces (velocity write, ``cpSpaceStep``, position read, copies)
cost 3.8 µs per world-step, the position write alone 1.3 µs.

The fast path drives the same C iterator that :mod:`pymunk.batch` uses (``pmSpaceBodySetIteratorFuncBatched``)
with a float array that points straight into numpy memory — no per-body Python. It reaches it through pymunk's
private ``pymunk._chipmunk`` module (verified on pymunk 7.3.1; pinned ``>=7.3,<8``). The public fallback does the
same through :func:`pymunk.batch.set_space_bodies` (a few µs more per world); it is used when the private module is
missing, when :func:`use_fast_sync` turns the fast path off, or with ``CROWDBENCH_PURE_PYMUNK=1``. Both give
identical positions (tested).
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
import pymunk
import pymunk.batch as pmb

from crowdbench.geometry import Polygon

try:  # private to pymunk: the fast path only (see the module docstring)
    from pymunk._chipmunk import ffi, lib
except ImportError:  # pragma: no cover - a pymunk without it takes the public path
    ffi = lib = None

_FAST = {"enabled": lib is not None and os.environ.get("CROWDBENCH_PURE_PYMUNK", "") not in ("1", "true", "yes")}


def use_fast_sync(enabled: bool) -> bool:
    """Allow (``True``) or forbid the private fast synchronisation for worlds built from now on; returns the
    previous setting (always ``False`` without ``pymunk._chipmunk``)."""
    before = _FAST["enabled"]
    _FAST["enabled"] = bool(enabled) and lib is not None
    return before

AGENT_GROUP = 1
"""Agent shapes share this :class:`pymunk.ShapeFilter` group: pymunk never builds agent–agent contacts (collisions
are detected by the world's swept test); queries still see the agents."""


class PymunkWorlds:
    """``B`` pymunk spaces with ``A`` agent bodies each.

    Args:
        radii: Agent radii ``(A,)`` [m] (agent 0 is the robot).
        obstacles: Static obstacles, vertex lists [m].
        num_worlds: ``B``.

    """

    def __init__(self, radii: np.ndarray, obstacles: Sequence[Polygon], num_worlds: int) -> None:
        self.num_agents = A = len(radii)
        self.spaces = [self._build(radii, obstacles) for _ in range(num_worlds)]
        B = num_worlds
        slack = 8  # rows of headroom so the C array never reallocates away from numpy memory
        self._pos = np.zeros((B, A + slack, 2))
        self.fast = bool(_FAST["enabled"])
        """Whether this batch synchronises through the private fast path."""
        if not self.fast:
            return
        self._keep: list = []
        self._set_pos = [self._data(self._pos[b], pmb.BodyFields.POSITION) for b in range(B)]
        self._sync_calls = [(space._space, d, d.floatArray) for space, d in zip(self.spaces, self._set_pos,
                                                                                strict=True)]
        self._set_fn = ffi.addressof(lib, "pmSpaceBodySetIteratorFuncBatched")

    @staticmethod
    def _build(radii: np.ndarray, obstacles: Sequence[Polygon]) -> pymunk.Space:
        space = pymunk.Space()
        space.collision_slop = 0.005  # metres, not pixels
        bodies, shapes = [], []
        for a, r in enumerate(radii):
            body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            shape = pymunk.Circle(body, float(r))
            shape.collision_type = 1 if a == 0 else 2
            shape.filter = pymunk.ShapeFilter(group=AGENT_GROUP)
            space.add(body, shape)
            bodies.append(body)
            shapes.append(shape)
        for poly in obstacles:
            if len(poly) == 2:
                space.add(pymunk.Segment(space.static_body, poly[0], poly[1], 0.0))
            else:
                space.add(pymunk.Poly(space.static_body, list(poly)))
        buf = pmb.Buffer()
        pmb.get_space_bodies(space, pmb.BodyFields.BODY_ID, buf)
        order = np.frombuffer(buf.int_buf(), dtype=np.uintp).tolist()
        if order[: len(bodies)] != [b.id for b in bodies] or order[len(bodies):] not in ([], [space.static_body.id]):
            raise RuntimeError("pymunk.batch visits bodies in an unexpected order; cannot synchronise the world")
        space.agent_bodies = bodies
        space.agent_shapes = shapes
        return space

    def set_radii(self, world: int, radii: np.ndarray, slots: slice | int = slice(None)) -> None:
        """Give the agents ``slots`` of world ``world`` their radii from ``radii`` ``(A,)`` [m] (episodes with drawn
        pedestrian sizes)."""
        shapes = self.spaces[world].agent_shapes
        if isinstance(slots, (int, np.integer)):
            shapes[slots].unsafe_set_radius(float(radii[slots]))
            return
        for shape, r in zip(shapes[slots], radii[slots].tolist(), strict=True):
            if shape.radius != r:
                shape.unsafe_set_radius(r)

    def _data(self, rows: np.ndarray, field: pmb.BodyFields):
        fa = lib.pmFloatArrayNew(0)
        cbuf = ffi.from_buffer("cpFloat[]", rows)
        fa.arr, fa.max, fa.num = cbuf, rows.size, 0
        data = ffi.new("pmBatchedData *")
        data.fields, data.floatArray, data.intArray = field.value, fa, lib.pmIntArrayNew(0)
        self._keep.append((fa, cbuf, rows))
        return data

    def set_positions(self, worlds: np.ndarray, positions: np.ndarray) -> None:
        """Teleport agents of ``worlds`` (indices ``(k,)``) to ``positions`` ``(k, A, 2)`` [m]."""
        A = self.num_agents
        for b, p in zip(worlds, positions, strict=True):
            self._pos[b, :A] = p
            self._pos[b, A:] = 0.0  # the static body, if visited, stays at the origin
            if not self.fast:
                pmb.set_space_bodies(self.spaces[b], pmb.BodyFields.POSITION, self._buffer(self._pos[b]))
                continue
            d = self._set_pos[b]
            d.floatArray.num = 0
            lib.cpSpaceEachBody(self.spaces[b]._space, self._set_fn, d)

    @property
    def mirror(self) -> np.ndarray:
        """``(B, A + slack, 2)`` [m]: the rows the bodies are set from; the world's step kernel writes the new
        positions into ``mirror[:, :A]`` so that :meth:`sync` needs no copy."""
        return self._pos

    def sync(self, positions: np.ndarray | None = None) -> None:
        """Move every agent body to ``positions`` ``(B, A, 2)`` [m] (``None``: to what :attr:`mirror` holds): one C
        call per world (the world's motion kernel integrates ``p ← p + v·dt`` itself, bit for bit what
        ``cpSpaceStep`` does to a kinematic body)."""
        A = self.num_agents
        if positions is not None:
            self._pos[:, :A] = positions
        if not self.fast:
            for b, space in enumerate(self.spaces):
                pmb.set_space_bodies(space, pmb.BodyFields.POSITION, self._buffer(self._pos[b]))
            return
        set_fn, each = self._set_fn, lib.cpSpaceEachBody
        for space, d, read in self._sync_calls:
            read.num = 0  # the C iterator's read cursor into the position rows
            each(space, set_fn, d)

    @staticmethod
    def _buffer(rows: np.ndarray) -> pmb.Buffer:
        buf = pmb.Buffer()
        buf.set_float_buf(rows.reshape(-1))
        return buf

    def verify(self, world: int = 0) -> None:
        """Check the fast path against the public ``pymunk.batch`` API (raises ``RuntimeError`` on mismatch)."""
        buf = pmb.Buffer()
        pmb.get_space_bodies(self.spaces[world], pmb.BodyFields.POSITION, buf)
        public = np.frombuffer(buf.float_buf()).reshape(-1, 2)[: self.num_agents]
        mine = np.array([tuple(b.position) for b in self.spaces[world].agent_bodies])
        if not (np.array_equal(public, mine) and np.array_equal(public, self._pos[world, : self.num_agents])):
            raise RuntimeError("pymunk fast synchronisation disagrees with pymunk.batch")

