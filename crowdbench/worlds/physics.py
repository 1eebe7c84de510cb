"""pymunk side of the world: one :class:`pymunk.Space` per world, agents as KINEMATIC circle bodies, obstacles as
static segments/polygons, synchronised with the numpy state in one C call per world and direction.

The fast path drives the same C iterators that :mod:`pymunk.batch` uses (``pmSpaceBody{Set,Get}IteratorFuncBatched``)
with float arrays that point straight into numpy memory, so a world step costs one velocity write, one
``cpSpaceStep`` and one position read — no per-body Python. :meth:`PymunkWorlds.verify` cross-checks it against the
public ``pymunk.batch`` API at construction. Requires pymunk 7.x (pinned in ``pyproject.toml``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pymunk
import pymunk.batch as pmb
from pymunk._chipmunk import ffi, lib

from crowdbench.geometry import Polygon

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
        self._vel = np.zeros((B, A + slack, 2))
        self._pos = np.zeros((B, A + slack, 2))
        self._keep: list = []
        self._set_vel = [self._data(self._vel[b], pmb.BodyFields.VELOCITY) for b in range(B)]
        self._set_pos = [self._data(self._pos[b], pmb.BodyFields.POSITION) for b in range(B)]
        self._get_pos = [self._data(self._pos[b], pmb.BodyFields.POSITION) for b in range(B)]
        self._set_fn = ffi.addressof(lib, "pmSpaceBodySetIteratorFuncBatched")
        self._get_fn = ffi.addressof(lib, "pmSpaceBodyGetIteratorFuncBatched")

    @staticmethod
    def _build(radii: np.ndarray, obstacles: Sequence[Polygon]) -> pymunk.Space:
        space = pymunk.Space()
        space.collision_slop = 0.005  # metres, not pixels
        bodies = []
        for a, r in enumerate(radii):
            body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            shape = pymunk.Circle(body, float(r))
            shape.collision_type = 1 if a == 0 else 2
            shape.filter = pymunk.ShapeFilter(group=AGENT_GROUP)
            space.add(body, shape)
            bodies.append(body)
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
        return space

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
            d = self._set_pos[b]
            d.floatArray.num = 0
            lib.cpSpaceEachBody(self.spaces[b]._space, self._set_fn, d)

    def step(self, velocities: np.ndarray, dt: float) -> np.ndarray:
        """Give every agent its velocity ``(B, A, 2)`` [m/s], step every space by ``dt`` [s] and return the new
        positions ``(B, A, 2)`` [m] (pymunk integrates ``p ← p + v·dt``).
        """
        A = self.num_agents
        self._vel[:, :A] = velocities
        set_fn, get_fn, step = self._set_fn, self._get_fn, lib.cpSpaceStep
        for b, space in enumerate(self.spaces):
            sp = space._space
            d = self._set_vel[b]
            d.floatArray.num = 0
            lib.cpSpaceEachBody(sp, set_fn, d)
            step(sp, dt)
            g = self._get_pos[b]
            g.floatArray.num = 0
            lib.cpSpaceEachBody(sp, get_fn, g)
        return self._pos[:, :A].copy()

    def verify(self, world: int = 0) -> None:
        """Check the fast path against the public ``pymunk.batch`` API (raises ``RuntimeError`` on mismatch)."""
        buf = pmb.Buffer()
        pmb.get_space_bodies(self.spaces[world], pmb.BodyFields.POSITION, buf)
        public = np.frombuffer(buf.float_buf()).reshape(-1, 2)[: self.num_agents]
        mine = np.array([tuple(b.position) for b in self.spaces[world].agent_bodies])
        if not (np.array_equal(public, mine) and np.array_equal(public, self._pos[world, : self.num_agents])):
            raise RuntimeError("pymunk fast synchronisation disagrees with pymunk.batch")
