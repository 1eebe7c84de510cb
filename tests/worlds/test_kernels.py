"""The compiled hot path equals its plain numpy reference bit for bit: kernel by kernel on random inputs (walls,
inactive slots, ties, empty crowds), and whole worlds stepped through either."""

from __future__ import annotations

import numpy as np
import pymunk
import pytest

from crowdbench.config import WorldConfig
from crowdbench.humans import ResponsiveORCA, preferred_velocity
from crowdbench.humans.orca_kernel import orca_inputs
from crowdbench.humans.responsive import _latent_step, latent_step_reference
from crowdbench.robots import make_observation
from crowdbench.robots.observations import human_observations
from crowdbench.worlds import CrowdWorld, _kernels, reference
from crowdbench.worlds.layouts import LAYOUTS


def _scene(rng: np.random.Generator, B: int, A: int, spread: float = 4.0):
    pos = rng.uniform(-spread, spread, (B, A, 2))
    near = pos[:, 1:3]
    near[:] = pos[:, :1] + rng.uniform(-0.5, 0.5, near.shape)  # some pedestrians close to the robot
    if A > 4:
        pos[:, 4] = pos[:, 3]  # exact distance ties
    vel = rng.uniform(-2.0, 2.0, (B, A, 2))
    goal = pos + rng.uniform(-1.0, 1.0, (B, A, 2)) * rng.choice([0.2, 3.0], (B, A, 1))
    radius = rng.uniform(0.2, 0.5, (B, A))
    v_pref = rng.uniform(0.5, 1.5, (B, A))
    active = rng.random((B, A)) < 0.8
    active[:, 0] = True
    return pos, vel, goal, radius, v_pref, active


EDGES = {"none": np.zeros((0, 2, 2)),
         "walls": np.array([[[-3.0, -3.0], [3.0, -3.0]], [[3.0, -3.0], [3.0, 3.0]], [[0.0, -1.0], [0.0, 1.0]],
                            [[-1.0, 2.0], [1.0, 2.5]]])}


@pytest.mark.parametrize("edges", sorted(EDGES))
@pytest.mark.parametrize("clip_robot", [True, False])
@pytest.mark.parametrize("seed", range(6))
def test_motion_kernel_equals_reference(edges, clip_robot, seed):
    rng = np.random.default_rng(seed)
    B, A = int(rng.integers(1, 5)), int(rng.integers(1, 12))
    pos, vel, _, radius, v_pref, active = _scene(rng, B, A)
    pos[0, 0], vel[0, 0], radius[0, 0], v_pref[0, 0] = (-0.45, 0.0), (0.9, 0.1), 0.3, 1.0  # runs into x = 0
    out = []
    for fn in (_kernels.motion, reference.motion):
        p, v = pos.copy(), vel.copy()
        disp, hit, d_min = np.empty_like(pos), np.empty(B, bool), np.empty(B)
        ok = fn(p, v, v_pref, radius, active, EDGES[edges], 0.25, 20, disp, hit, d_min, clip_robot)
        out.append((ok, p, v, disp, hit, d_min))
    for a, b in zip(*out, strict=True):
        np.testing.assert_array_equal(a, b)
    hit, v = out[0][4], out[0][2]
    assert hit[0] == (edges == "walls")
    if edges == "walls":
        assert v[0, 0, 0] == pytest.approx(0.6, abs=1e-5)  # stopped at contact: 0.15 m of 0.225 m in 0.25 s


def test_motion_kernel_refuses_non_finite_pedestrian_velocities_without_moving_anything():
    rng = np.random.default_rng(0)
    pos, vel, _, radius, v_pref, active = _scene(rng, 2, 6)
    active[1, 3] = True
    vel[1, 3, 0] = np.nan
    p, v = pos.copy(), vel.copy()
    ok = _kernels.motion(p, v, v_pref, radius, active, EDGES["none"], 0.25, 20, np.empty_like(pos), np.empty(2, bool),
                         np.empty(2), True)
    assert not ok
    np.testing.assert_array_equal(p, pos)
    assert not reference.motion(pos.copy(), vel.copy(), v_pref, radius, active, EDGES["none"], 0.25, 20,
                                np.empty_like(pos), np.empty(2, bool), np.empty(2), True)


def test_kernel_integration_is_pymunks_kinematic_step():
    """The motion kernel's ``p + v·dt`` is what ``cpSpaceStep`` computes for a kinematic body, bit for bit."""
    rng = np.random.default_rng(3)
    pos, vel = rng.uniform(-50, 50, (200, 2)), rng.uniform(-2, 2, (200, 2))
    space = pymunk.Space()
    bodies = []
    for p, v in zip(pos, vel, strict=True):
        body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        body.position, body.velocity = tuple(p), tuple(v)
        space.add(body, pymunk.Circle(body, 0.3))
        bodies.append(body)
    space.step(0.25)
    p = pos[None].copy()
    ok = _kernels.motion(p, vel[None].copy(), np.full((1, 200), 1e9), np.full((1, 200), 0.3), np.ones((1, 200), bool),
                         EDGES["none"], 0.25, 20, np.empty_like(p), np.empty(1, bool), np.empty(1), False)
    assert ok
    np.testing.assert_array_equal(p[0], np.array([tuple(b.position) for b in bodies]))


@pytest.mark.parametrize("seed", range(8))
def test_outcome_kernel_equals_reference(seed):
    rng = np.random.default_rng(seed)
    B, A = int(rng.integers(1, 6)), int(rng.integers(1, 10))
    pos, vel, goal, radius, _, active = _scene(rng, B, A)
    goal[:, 0] = pos[:, 0] + rng.uniform(-0.4, 0.4, (B, 2))  # some robots within the goal tolerance
    vel[rng.random((B, A)) < 0.2] = 0.0
    d_min = rng.choice([-0.1, 0.0, 0.1, 0.3, np.inf], B)
    hit = rng.random(B) < 0.2
    rw = np.array([10.0, -20.0, 0.25, 10.0, 4.0, -0.025, 0.3])
    heading0 = rng.uniform(-np.pi, np.pi, (B, A))
    out = []
    for fn in (_kernels.outcome, reference.outcome):
        steps = rng.integers(0, 10, B) if fn is _kernels.outcome else out[0][-1]
        st, prev = steps.copy(), np.full(B, 2.0)
        arrays = (heading0.copy(), np.empty((5, B)), np.empty(B), np.empty(B, np.int64), np.empty(B, bool),
                  np.empty(B, bool), np.empty(B, np.int64), np.empty((B, A - 1), bool), np.empty(B, bool))
        heading, terms, reward, result, term, trunc, overlaps, reached, due = arrays
        events = fn(pos, vel, goal, radius, active, heading, st, prev, d_min, hit, bool(seed % 2), 5, rw, 3, terms,
                    reward, result, term, trunc, overlaps, reached, due)
        out.append((events, st, prev, *arrays, steps))
    for a, b in zip(out[0][:-1], out[1][:-1], strict=True):
        np.testing.assert_array_equal(a, b)
    rest = (vel == 0.0).all(-1)
    if seed % 2:  # a unicycle robot keeps the heading its action set
        rest[:, 0] = True
    np.testing.assert_array_equal(out[0][3][rest], heading0[rest])  # resting agents keep their heading
    np.testing.assert_allclose(out[0][3][~rest], np.arctan2(vel[..., 1], vel[..., 0])[~rest], rtol=1e-15)


@pytest.mark.parametrize("features,max_range", [(2, 5.0), (5, np.inf), (2, 0.0)])
@pytest.mark.parametrize("slots", [3, 30])
@pytest.mark.parametrize("by_id", [False, True])
@pytest.mark.parametrize("seed", range(4))
def test_robot_observation_kernel_equals_reference(features, max_range, slots, by_id, seed):
    rng = np.random.default_rng(seed)
    B, A = int(rng.integers(1, 5)), int(rng.integers(1, 12))
    pos, vel, goal, radius, v_pref, active = _scene(rng, B, A)
    heading = rng.uniform(-3, 3, (B, A))
    out = []
    for fn in (_kernels.robot_observation, reference.robot_observation):
        arrays = (np.empty((B, 9), np.float32), np.empty((B, slots, features), np.float32),
                  np.empty((B, slots), np.float32))
        fn(pos, vel, goal, radius, v_pref, heading, active, max_range, by_id, *arrays)
        out.append(arrays)
    for a, b in zip(*out, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("seed", range(6))
def test_assign_slots_kernel_equals_reference(seed):
    """Over a sequence of steps (views changing, re-spawns, a new episode, a repeated call), the compiled slot
    lending and its plain statement keep the same state."""
    rng = np.random.default_rng(seed)
    B, H, n = 3, int(rng.integers(4, 20)), int(rng.integers(1, 6))
    states = [(np.full((B, n), -1, np.int64), np.full((B, H), -1, np.int64), np.zeros((B, H), np.int64),
               np.full(B, -2, np.int64)) for _ in range(2)]
    spawns, steps = np.zeros((B, H), np.int64), np.zeros(B, np.int64)
    for t in range(30):
        seen = rng.random((B, H)) < 0.6
        dist = rng.choice([0.5, 1.0, 2.0, 3.0], (B, H))  # ties: broken by index
        spawns += rng.random((B, H)) < 0.05
        steps = np.where(rng.random(B) < 0.1, 0, steps + (t % 7 != 3))  # restarts and repeated steps
        for fn, state in zip((_kernels.assign_slots, reference.assign_slots), states, strict=True):
            fn(seen, dist, spawns, steps, *state)
        for a, b in zip(*states, strict=True):
            np.testing.assert_array_equal(a, b)
        who, slot_of = states[0][:2]
        held = who >= 0
        assert seen[np.arange(B)[:, None], np.where(held, who, 0)][held].all()  # slots hold people in view
        assert (held.sum(1) == np.minimum(n, seen.sum(1))).all()  # no slot idle while someone in view waits


@pytest.mark.parametrize("visible", [True, False])
@pytest.mark.parametrize("slots", [2, 30])
@pytest.mark.parametrize("seed", range(4))
def test_human_observation_kernel_equals_reference(visible, slots, seed):
    rng = np.random.default_rng(seed)
    B, A = 3, int(rng.integers(1, 14))
    pos, vel, goal, radius, v_pref, active = _scene(rng, B, A)
    heading = rng.uniform(-3, 3, (B, A))
    out = []
    for fn in (_kernels.human_observation, reference.human_observation):
        arrays = (np.empty((A - 1, 9), np.float32), np.empty((A - 1, slots, 5), np.float32),
                  np.empty((A - 1, slots), np.float32))
        fn(pos, vel, goal, radius, v_pref, heading, active, seed % B, 3.0, visible, *arrays)
        out.append(arrays)
    for a, b in zip(*out, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("seed", range(20))
def test_first_clear_kernel_equals_reference(seed):
    rng = np.random.default_rng(seed)
    A = int(rng.integers(1, 25))
    pos, _, _, radius, _, active = (x[0] for x in _scene(rng, 1, A, spread=3.0 if seed % 2 else 0.8))
    starts = rng.uniform(-3.5, 3.5, (16, 2)) * (1.0 if seed % 2 else 0.3)  # odd: room; even: often nowhere (→ 15)
    agent = int(rng.integers(0, A))
    assert _kernels.first_clear(starts, pos, radius, active, agent, 0.1) == reference.first_clear(
        starts, pos, radius, active, agent, 0.1)


@pytest.mark.parametrize("pref_speed", [0.0, 1.0])
def test_orca_inputs_kernel_equals_numpy(pref_speed):
    rng = np.random.default_rng(0)
    B, H = 3, 9
    pos, vel, goal, radius, v_pref, active = _scene(rng, B, H + 1)
    goal[:, 1:4] = pos[:, 1:4] + rng.uniform(-0.6, 0.6, (B, 3, 2))  # some goals within 1 m
    ignore_robot = rng.random((B, H)) < 0.5
    outs = (np.zeros((B, H + 1, 2)), np.zeros((B, H + 1, 2)), np.zeros((B, H + 1, 2)), np.zeros((B, H + 1)),
            np.zeros((B, H + 1)), np.zeros((B, H + 1), bool), np.zeros((B, H + 1), np.int64))
    orca_inputs(pos[:, 0], vel[:, 0], radius[:, 0], pos[:, 1:], vel[:, 1:], goal[:, 1:], radius[:, 1:], v_pref[:, 1:],
                active[:, 1:], ignore_robot, 0.16, 0.25, pref_speed, *outs)
    p, v, pref, rad, vmax, act, ignore = outs
    np.testing.assert_array_equal(p, pos)
    np.testing.assert_array_equal(v, vel)
    if pref_speed:  # CrowdNav++: the goal vector cut to 1 m/s, the raw vector within 1 m; v_pref is the limit
        d = goal[:, 1:] - pos[:, 1:]
        dist = np.linalg.norm(d, axis=-1, keepdims=True)
        np.testing.assert_allclose(pref[:, 1:], np.where(dist > 1.0, d / dist, d), rtol=1e-15, atol=1e-15)
    else:
        np.testing.assert_array_equal(pref[:, 1:], preferred_velocity(pos[:, 1:], goal[:, 1:], v_pref[:, 1:], 0.25))
    np.testing.assert_array_equal(rad, radius + 0.16)
    np.testing.assert_array_equal(vmax[:, 1:], v_pref[:, 1:])
    np.testing.assert_array_equal(act[:, 1:], active[:, 1:])
    np.testing.assert_array_equal(ignore[:, 1:], np.where(ignore_robot, 0, -1))
    assert act[:, 0].all() and (ignore[:, 0] == -1).all()


@pytest.mark.parametrize("fov", [np.pi, 2 * np.pi])
def test_latent_step_kernel_equals_reference(fov):
    B, H, K = 4, 12, 3
    rng = np.random.default_rng(1)

    class State:
        robot_visible = True

    models = []
    for _ in range(2):
        m = ResponsiveORCA(responsiveness=0.5, fov=fov, debounce=K)
        m.bind(B, H, (), 0.25)
        m.reset(np.arange(B), [np.random.default_rng(b) for b in range(B)], State)
        models.append(m)
    fast, ref = models
    for t in range(40):
        pos, _, _, _, _, active = _scene(rng, B, H + 1, spread=6.0)
        State.robot_position, State.positions, State.active = pos[:, 0], pos[:, 1:], active[:, 1:]
        State.headings = rng.uniform(-np.pi, np.pi, (B, H))
        u = rng.random((B, 1, H))
        ignored = np.empty((B, H), bool)
        _latent_step(State.robot_position, State.positions, State.headings, State.active, True, fov, 5.0, u,
                     np.zeros(B, np.int64), fast.rho_i, fast.xi, fast._streak, fast._fresh, K, fast.visible, ignored)
        expected = latent_step_reference(ref, State, u[:, 0])
        np.testing.assert_array_equal(ignored, expected)
        for name in ("visible", "xi", "_streak", "_fresh"):
            np.testing.assert_array_equal(getattr(fast, name), getattr(ref, name), err_msg=f"{name} at step {t}")


def _rollout(layout: str, **config) -> list[np.ndarray]:
    w = CrowdWorld(WorldConfig(num_humans=12, time_limit=20.0, **config), 3, layout, "responsive_orca")
    w.reset(seeds=[4, 5, 6])
    obs = make_observation("full_state", w.config)
    rng = np.random.default_rng(0)
    out = []
    for t in range(100):
        r = w.step(rng.uniform(-1.2, 1.2, (3, 2)))
        o = obs.build(w)
        h = human_observations(w, 1)
        out += [w.pos.copy(), w.vel.copy(), w.heading.copy(), w.goal.copy(), r.reward, r.d_min, r.outcome,
                r.human_overlaps, *o.values(), *h.values()]
        done = r.terminated | r.truncated
        if done.any():
            w.reset(seeds=list(np.flatnonzero(done) + 10 * t), mask=done)
    return out


@pytest.mark.parametrize("layout,config", [("circle_crossing", {}), ("intersection", {"arena_walls": True}),
                                           ("split_flow", {"kinematics": "unicycle"})])
def test_world_through_kernels_equals_world_through_reference(layout, config, monkeypatch):
    assert layout in LAYOUTS.names()
    fast = _rollout(layout, **config)
    import crowdbench.robots.observations as observations
    import crowdbench.worlds.world as world

    monkeypatch.setattr(world, "advance", reference.advance)
    monkeypatch.setattr(observations, "robot_observation", reference.robot_observation)
    monkeypatch.setattr(observations, "human_observation", reference.human_observation)
    slow = _rollout(layout, **config)
    assert len(fast) == len(slow)
    for a, b in zip(fast, slow, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("name", ["relative", "relative_by_id", "full_state", "predicted"])
@pytest.mark.parametrize("slots", [30, 5])
def test_one_world_observations_in_one_call_equal_builder_and_pedestrian_kernels(name, slots):
    from crowdbench.robots.observations import agent_observations

    w = CrowdWorld(WorldConfig(num_humans=9, humans_range=(4, 9), max_humans_observed=slots), 1, "circle_crossing",
                   "responsive_orca")
    builder, twin = make_observation(name, w.config), make_observation(name, w.config)  # (stateful builders)
    rng = np.random.default_rng(1)
    for t in range(60):
        if t % 20 == 0:
            w.reset(seeds=[t])
        w.step(rng.uniform(-1.2, 1.2, (1, 2)))
        robot, humans = agent_observations(builder, w)
        for got, want in ((robot, twin.build(w)), (humans, human_observations(w, 0))):
            assert got.keys() == want.keys()
            for k in got:
                np.testing.assert_array_equal(got[k], want[k])


def test_a_builder_subclass_that_overrides_build_is_not_bypassed():
    from crowdbench.robots.observations import RelativeObservation, agent_observations

    class Shifted(RelativeObservation):
        def build(self, world):
            out = super().build(world)
            out["robot"] += 1.0
            return out

    w = CrowdWorld(WorldConfig(num_humans=5), 1, "circle_crossing", "orca")
    w.step(np.zeros((1, 2)))
    robot, _ = agent_observations(Shifted(w.config), w)
    np.testing.assert_array_equal(robot["robot"], RelativeObservation(w.config).build(w)["robot"] + 1.0)
