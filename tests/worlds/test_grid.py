"""The world's grid paths (:mod:`crowdbench.spatial` cell lists, above ``GRID_MIN`` agents) equal its brute-force
paths bit for bit: pedestrian and agent observations (same neighbours, same nearest-first order, ties by index),
pedestrian clearance and contacts, overlap counting — at N = 200 and 1,000, in the concourse and in random dense
crowds with exact distance ties, inactive agents, and the robot visible, invisible or far away."""

from __future__ import annotations

import numpy as np
import pytest

import crowdbench
from crowdbench.config import WorldConfig
from crowdbench.geometry import pair_overlaps
from crowdbench.spatial import GRID_MIN
from crowdbench.worlds import CrowdWorld, _kernels, reference
from crowdbench.worlds.reference import BRUTE_FORCE

SLOTS = 30


def _dense(n: int, seed: int, robot: str) -> tuple[np.ndarray, ...]:
    """One world of ``1 + n`` agents: a random dense crowd (about 2.5 people/m², overlaps allowed), a quarter of it
    on a 0.5 m lattice (exact distance ties everywhere), some duplicated positions, 10 % inactive and parked far
    away; the robot ``"near"`` the crowd or ``"far"`` (a huge bounding box)."""
    rng = np.random.default_rng(seed)
    side = np.sqrt(n / 2.5)
    pos = rng.uniform(-side / 2, side / 2, (1, n + 1, 2))
    k = n // 4
    g = int(np.ceil(np.sqrt(k)))
    lattice = np.stack(np.meshgrid(np.arange(g), np.arange(g)), -1).reshape(-1, 2)[:k] * 0.5 - g * 0.25
    pos[0, 1:k + 1] = lattice
    pos[0, k + 1:k + 11] = pos[0, k + 11:k + 21]  # the same spot twice
    pos[0, 0] = (0.1, -0.2) if robot == "near" else (1e4, 1e4)
    active = rng.random((1, n + 1)) > 0.1
    active[0, 0] = True
    pos[0, ~active[0]] = 1e4 + 3.0 * np.arange(int((~active[0]).sum()))[:, None]
    vel = rng.uniform(-1.5, 1.5, (1, n + 1, 2))
    goal = pos + rng.uniform(-3, 3, (1, n + 1, 2))
    radius = rng.uniform(0.2, 0.3, (1, n + 1))
    radius[0, k + 1:k + 6] = 0.25  # equal radii: equal surface distances too
    v_pref = rng.uniform(0.5, 1.5, (1, n + 1))
    heading = rng.uniform(-np.pi, np.pi, (1, n + 1))
    return pos, vel, goal, radius, v_pref, heading, active


def _concourse(n: int, steps: int) -> tuple[np.ndarray, ...]:
    """The concourse after ``steps`` steps of the ORCA crowd (radii 0.2–0.3 m at N = 1,000, as its layout asks)."""
    extra = {"human_radius_range": (0.2, 0.3)} if n > 500 else {}
    w = CrowdWorld(WorldConfig(num_humans=n, **extra), 1, "concourse", "orca")
    w.reset(seeds=[n])
    rng = np.random.default_rng(0)
    for _ in range(steps):
        w.step(rng.uniform(-1.0, 1.0, (1, 2)))
    return w.pos.copy(), w.vel.copy(), w.goal.copy(), w.radius.copy(), w.v_pref.copy(), w.heading.copy(), \
        w.active.copy()


SCENES = {
    "concourse": lambda n: _concourse(n, 3),
    "dense": lambda n: _dense(n, n, "near"),
    "dense_robot_far": lambda n: _dense(n, n + 1, "far"),
}


@pytest.fixture(scope="module", params=[(s, n) for s in sorted(SCENES) for n in (200, 1000)],
                ids=lambda p: f"{p[0]}-{p[1]}")
def scene(request):
    name, n = request.param
    arrays = SCENES[name](n)
    assert arrays[-1].sum() > GRID_MIN  # the grid path is the one taken by default
    return arrays


@pytest.mark.parametrize("visible", [True, False])
def test_pedestrian_observations_grid_equals_brute_force(scene, visible):
    pos, vel, goal, radius, v_pref, heading, active = scene
    H = pos.shape[1] - 1
    out = []
    for grid_min in (GRID_MIN, BRUTE_FORCE):
        arrays = (np.empty((H, 9), np.float32), np.empty((H, SLOTS, 5), np.float32), np.empty((H, SLOTS), np.float32))
        _kernels.human_observation(pos, vel, goal, radius, v_pref, heading, active, 0, 5.0, visible, *arrays,
                                   grid_min)
        out.append(arrays)
    for a, b in zip(*out, strict=True):
        np.testing.assert_array_equal(a, b)
    seen = out[0][2].sum(1)
    assert seen.max() == SLOTS or H < 1000  # crowded: some see more pedestrians than they have slots for


def test_pedestrian_observations_grid_equals_numpy_reference(scene):
    pos, vel, goal, radius, v_pref, heading, active = scene
    H = pos.shape[1] - 1
    out = []
    for fn in (_kernels.human_observation, reference.human_observation):
        arrays = (np.empty((H, 9), np.float32), np.empty((H, SLOTS, 5), np.float32), np.empty((H, SLOTS), np.float32))
        fn(pos, vel, goal, radius, v_pref, heading, active, 0, 5.0, True, *arrays)
        out.append(arrays)
    for a, b in zip(*out, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("visible", [True, False])
@pytest.mark.parametrize("sensing_range", [1.0, 5.0, np.inf])
def test_agent_observations_grid_equals_brute_force(scene, visible, sensing_range):
    """Every agent (the robot too) in the pedestrians' layout; inactive agents observe zeros; a batch of two worlds
    (the second: the first with everyone but the robot inactive, below the grid's threshold)."""
    pos, vel, goal, radius, v_pref, heading, active = (np.concatenate([x, x]) for x in scene)
    active[1, 1:] = False
    B, A = active.shape
    out = []
    for grid_min in (GRID_MIN, BRUTE_FORCE):
        arrays = (np.empty((B, A, 9), np.float32), np.empty((B, A, SLOTS, 5), np.float32),
                  np.empty((B, A, SLOTS), np.float32))
        _kernels.agent_observations_batch(pos, vel, goal, radius, v_pref, heading, active, sensing_range, visible,
                                          *arrays, grid_min)
        out.append(arrays)
    for a, b in zip(*out, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("visible", [True, False])
def test_crowd_clearance_grid_equals_brute_force(scene, visible):
    pos, _, _, radius, _, _, active = scene
    H = pos.shape[1] - 1
    out = []
    for grid_min in (GRID_MIN, BRUTE_FORCE):
        arrays = (np.empty((1, H)), np.empty((1, H), bool), np.empty((1, H), bool))
        _kernels.crowd_clearance(pos, radius, active, visible, *arrays, grid_min)
        out.append(arrays)
    for a, b in zip(*out, strict=True):
        np.testing.assert_array_equal(a, b)
    near = out[0][0][0]
    assert np.isinf(near[~active[0, 1:]]).all() and np.isfinite(near[active[0, 1:]]).all()


def test_crowd_clearance_of_a_sparse_crowd_searches_beyond_the_first_disc():
    """Pedestrians many cells apart (the nearest one far beyond the first disc searched) and one alone in its
    world's half: the second, wider search finds the same minimum."""
    rng = np.random.default_rng(3)
    n = 150
    pos = np.concatenate([rng.uniform(-50, 50, (1, n, 2)), [[[200.0, 200.0]]]], 1)
    pos[0, 0] = (1e4, 1e4)
    radius, active = np.full((1, n + 1), 0.3), np.ones((1, n + 1), bool)
    out = []
    for grid_min in (GRID_MIN, BRUTE_FORCE):
        arrays = (np.empty((1, n)), np.empty((1, n), bool), np.empty((1, n), bool))
        _kernels.crowd_clearance(pos, radius, active, True, *arrays, grid_min)
        out.append(arrays)
    for a, b in zip(*out, strict=True):
        np.testing.assert_array_equal(a, b)


def test_pair_overlaps_grid_equals_brute_force(scene):
    pos, _, _, radius, _, _, active = scene
    got = pair_overlaps(pos[:, 1:], radius[:, 1:], active[:, 1:], GRID_MIN)
    want = pair_overlaps(pos[:, 1:], radius[:, 1:], active[:, 1:], BRUTE_FORCE)
    np.testing.assert_array_equal(got, want)


def test_a_non_finite_position_takes_the_brute_force_path():
    pos, vel, goal, radius, v_pref, heading, active = _dense(200, 7, "near")
    pos[0, 5] = (np.nan, 0.0)
    H = pos.shape[1] - 1
    out = []
    for grid_min in (GRID_MIN, BRUTE_FORCE):
        arrays = (np.empty((H, 9), np.float32), np.empty((H, SLOTS, 5), np.float32), np.empty((H, SLOTS), np.float32))
        _kernels.human_observation(pos, vel, goal, radius, v_pref, heading, active, 0, 5.0, True, *arrays, grid_min)
        clear = (np.empty((1, H)), np.empty((1, H), bool), np.empty((1, H), bool))
        _kernels.crowd_clearance(pos, radius, active, True, *clear, grid_min)
        out.append((*arrays, *clear, pair_overlaps(pos[:, 1:], radius[:, 1:], active[:, 1:], grid_min)))
    for a, b in zip(*out, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("robot", ["agent", None])
def test_pettingzoo_world_grid_equals_brute_force(robot):
    """Twelve steps of the PettingZoo concourse at N = 200 (every agent's observation, rewards, infos), once with
    the grid and once with brute force everywhere (``world.grid_min``); ``robot=None``: the robot invisible."""
    runs = []
    for grid_min in (GRID_MIN, BRUTE_FORCE):
        env = crowdbench.parallel_env(layout="concourse", num_humans=200, robot=robot, seed=3)
        env.world.grid_min = grid_min
        obs, _ = env.reset()
        steps = [obs]
        for _ in range(12):
            actions = {"robot": np.array([0.5, 0.2])} if robot else {}
            actions["human_7"] = np.array([0.3, -0.9])
            steps.append(env.step(actions))
        runs.append(steps)
    for a, b in zip(*runs, strict=True):
        _assert_same(a, b)


def _assert_same(a, b) -> None:
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for k in a:
            _assert_same(a[k], b[k])
    elif isinstance(a, (tuple, list)):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            _assert_same(x, y)
    else:
        np.testing.assert_array_equal(a, b)
