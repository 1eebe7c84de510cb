"""Malformed inputs wherever users type them — ``parallel_env``, the Gymnasium ids, layouts, pedestrian models, robot
policies, suite files, the CLI: each input is either accepted (and the thing then runs) or answered by one
``ValueError``/``TypeError`` whose message names what was wrong; never another exception, never a hang (20 s).

The counts of inputs tried and of each answer are printed at the end (``pytest -s tests/test_fuzz_inputs.py``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import signal
from collections import Counter, defaultdict

import gymnasium
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numba.core import event as numba_event

import crowdbench
from crowdbench.cli import main
from crowdbench.config import WorldConfig
from crowdbench.humans import HUMAN_MODELS
from crowdbench.humans import make as make_model
from crowdbench.policies import make_policy
from crowdbench.robots import make_observation
from crowdbench.worlds import LAYOUTS, CrowdWorld, make_layout

ANSWERS: dict[str, Counter] = defaultdict(Counter)
KINDS = ("pedestrian model", "layout", "robot observation", "robot policy", "suite")
"""Registry errors name the kind of plug-in ("unknown layout 'x'; valid choices: …"): that names the input too."""

JUNK = st.one_of(
    st.none(), st.booleans(), st.integers(-10**9, 10**9), st.sampled_from([-1, 0, 1, 2, 3, 31, 1001]),
    st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([-0.5, 0.0, 0.25, 0.5, 1.0, 7.0]),
    st.text(max_size=4), st.lists(st.integers(-2, 40), max_size=3), st.lists(st.floats(-1, 40), max_size=3),
    st.dictionaries(st.text(max_size=3), st.integers(-2, 3), max_size=2),
)
FUZZ = settings(max_examples=120, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)


class _Compiling(numba_event.Listener):
    """How many numba compilations are running (``numba:compile`` events): compiling is not a hang."""

    depth = 0

    def on_start(self, event: numba_event.Event) -> None:
        _Compiling.depth += 1

    def on_end(self, event: numba_event.Event) -> None:
        _Compiling.depth -= 1


numba_event.register("numba:compile", _Compiling())


@contextlib.contextmanager
def time_limit(seconds: int):
    def hang(*_):
        if _Compiling.depth > 0:  # a fuzzed input's new argument types compile a kernel: wait for it (on a loaded
            signal.alarm(seconds)  # machine that takes longer than the limit, and an alarm inside numba's compiler
            return  # would leave it half-built)
        raise TimeoutError(f"no answer within {seconds} s: a hang")

    old = signal.signal(signal.SIGALRM, hang)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@pytest.fixture(scope="module", autouse=True)
def compiled_kernels():
    """Compile the world's and the pedestrian models' kernels and the planners' policies before any hang guard runs
    (on a fresh clone nothing is cached: compiling is not a hang, and an alarm inside numba's compiler would leave
    it half-built)."""
    cfg = WorldConfig(num_humans=4)
    for model in ("orca", "social_force", "responsive_orca"):
        world = CrowdWorld(cfg, 2, "circle_crossing", model)
        for name in ("orca", "social_force", "linear", "h2int"):
            policy = make_policy(name, cfg)
            world.step(policy.act(make_observation(policy.observation, cfg).build(world)))
    for layout in LAYOUTS.names():
        with contextlib.suppress(ValueError, TypeError):
            CrowdWorld(cfg, 1, layout, "orca").step(np.zeros((1, 2)))
    env = crowdbench.parallel_env(num_humans=4)
    env.reset(seed=0)
    env.step({a: env.action_space(a).sample() for a in env.agents})


def names_of(kwargs: dict) -> set[str]:
    out = set()
    for k, v in kwargs.items():
        out.add(str(k))
        if isinstance(v, dict):
            out |= names_of(v)
    return out


def answer(target: str, run, kwargs: dict, words: tuple[str, ...] = ()) -> None:
    """Run ``run()``; record and check the answer: accepted, or a clear ValueError/TypeError."""
    try:
        with time_limit(20), np.errstate(all="raise"):
            run()
    except (ValueError, TypeError) as e:
        msg = str(e)
        named = names_of(kwargs) | set(words) | set(KINDS)
        assert any(n and n in msg for n in named), f"{target}{kwargs}: the error does not name the input: {msg!r}"
        assert "\n" not in msg.strip(), f"{target}{kwargs}: not one line: {msg!r}"
        ANSWERS[target][type(e).__name__] += 1
        return
    ANSWERS[target]["accepted"] += 1


@pytest.fixture(scope="module", autouse=True)
def report():
    yield
    total = sum(sum(c.values()) for c in ANSWERS.values())
    print(f"\nfuzzed inputs: {total}")
    for target, c in sorted(ANSWERS.items()):
        print(f"  {target:<16} {sum(c.values()):>4} tried: " + ", ".join(f"{k} {v}" for k, v in sorted(c.items())))


WORLD_FIELDS = [f.name for f in dataclasses.fields(WorldConfig)]
ENV_ARGS = [*WORLD_FIELDS, "layout", "human_model", "observation", "max_cycles", "render_mode", "seed",
            "human_model_kwargs", "no_such_option"]


def kwargs_from(keys: list[str]):
    return st.dictionaries(st.sampled_from(keys), JUNK, min_size=1, max_size=3)


def step_env(env) -> None:
    env.reset(seed=0)
    env.step({"robot": np.zeros(2)})


@FUZZ
@given(kwargs_from(ENV_ARGS))
def test_parallel_env(kwargs):
    answer("parallel_env", lambda: step_env(crowdbench.parallel_env(**kwargs)), kwargs)


@FUZZ
@given(kwargs_from([*WORLD_FIELDS, "human_model", "observation", "no_such_option"]))
def test_gymnasium_ids(kwargs):
    def run():
        env = gymnasium.make("crowdbench/CircleCrossing-v0", **kwargs)
        env.reset(seed=0)
        env.step(np.zeros(2, np.float32))

    answer("gymnasium.make", run, kwargs, ("crowdbench",))


LAYOUT_ARGS = ["radius", "noise", "arrival", "robot", "robot_area", "robot_min_distance", "goal_change_interval",
               "goal_change_prob", "width", "extent", "bogus"]


@FUZZ
@given(st.one_of(st.sampled_from(LAYOUTS.names()), st.text(max_size=4)), kwargs_from(LAYOUT_ARGS))
def test_layouts(name, kwargs):
    def run():
        CrowdWorld(WorldConfig(num_humans=5), 1, make_layout(name, **kwargs), "orca").step(np.zeros((1, 2)))

    answer("layouts", run, kwargs, ("layout",))


MODEL_ARGS = ["responsiveness", "spread", "fov", "sensing_range", "debounce", "neighbor_dist", "max_neighbors",
              "time_horizon", "time_horizon_obst", "radius_pad", "safety_space", "A", "B", "KI", "wall_A", "wall_B",
              "bogus"]


@FUZZ
@given(st.one_of(st.sampled_from(HUMAN_MODELS.names()), st.text(max_size=4)), kwargs_from(MODEL_ARGS))
def test_pedestrian_models(name, kwargs):
    def run():
        CrowdWorld(WorldConfig(num_humans=4), 1, "circle_crossing", make_model(name, **kwargs)).step(np.zeros((1, 2)))

    answer("pedestrian model", run, kwargs, ("pedestrian model",))


POLICY_ARGS = ["neighbor_dist", "max_neighbors", "time_horizon", "safety_space", "A", "B", "KI", "gamma",
               "sensing_range", "checkpoint", "bogus"]


@FUZZ
@given(st.sampled_from(["orca", "social_force", "linear", "h2int", "nope"]), kwargs_from(POLICY_ARGS))
def test_robot_policies(name, kwargs):
    def run():
        cfg = WorldConfig(num_humans=4)
        policy = make_policy(name, cfg, **kwargs)
        world = CrowdWorld(cfg, 2, "circle_crossing", "orca")
        world.step(policy.act(make_observation(policy.observation, cfg).build(world)))

    answer("robot policy", run, kwargs, ("robot policy", "checkpoint"))


SUITE_KEYS = ["name", "description", "episodes", "seed", "tables", "rows", "worlds", "counterfactual", "bogus"]


def toml_value(v) -> str | None:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(float(v)) if isinstance(v, float) and np.isfinite(v) else (str(v) if isinstance(v, int) else None)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list):
        parts = [toml_value(x) for x in v]
        return None if None in parts or len({type(x) for x in v}) > 1 else "[" + ", ".join(parts) + "]"
    return None


@FUZZ
@given(kwargs_from(SUITE_KEYS))
def test_suite_files(tmp_path_factory, kwargs):
    from crowdbench import leaderboard

    lines = [f"{k} = {toml_value(v)}" for k, v in kwargs.items() if toml_value(v) is not None]
    path = tmp_path_factory.mktemp("suite") / "s.toml"
    path.write_text("\n".join(lines) + "\n")
    answer("suite file", lambda: leaderboard.load_suite(str(path)).grid(), kwargs, ("suite",))


CLI_JUNK = st.sampled_from(["-1", "0", "x", "nan", "1e9", "", "2.5", "--", "inf"])


@FUZZ
@given(st.sampled_from(["evaluate", "render", "train", "tables", "leaderboard run", "leaderboard paper", "panels",
                        "export"]),
       st.lists(st.tuples(st.sampled_from(["--episodes", "--humans", "--layout", "--human-model", "--responsiveness",
                                           "--seed", "--worlds", "--policy", "--checkpoint", "--suite", "--methods",
                                           "--workers", "--backend", "--iterations", "--envs", "--steps", "--bogus"]),
                          CLI_JUNK), min_size=1, max_size=3))
def test_cli(command, flags):
    argv = command.split()
    for flag, value in flags:
        argv += [flag, value]
    if command == "train":
        argv.insert(1, "h2int")
        argv += ["--envs", "-1"]  # never start a real training run
    if command in ("evaluate", "render", "panels", "tables", "leaderboard run"):
        argv += ["--episodes", "-1"] if "--episodes" not in argv else []

    def run():
        try:
            code = main(argv)
        except SystemExit as e:  # argparse: usage error, exit status 2 with one message
            code = e.code
        if code not in (0, 2):
            raise AssertionError(f"crowdbench {' '.join(argv)} exited with {code}")
        ANSWERS["cli"][f"exit {code}"] += 1

    with time_limit(60):
        run()
