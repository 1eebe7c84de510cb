"""Architecture guarantees: heavy libraries load lazily, learned methods resolve by name, running a policy needs
neither rsl-rl nor the training package, the layers import downward only (read from the source, every import
statement, function-local ones included), the core names no method, the shipped checkpoints are package data."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PROBE = """
import sys
{body}
heavy = sorted(m for m in ("torch", "rsl_rl", "tensordict") if m in sys.modules)
print("HEAVY=" + ",".join(heavy))
"""


def _heavy(body: str) -> str:
    out = subprocess.run([sys.executable, "-c", PROBE.format(body=body)], capture_output=True, text=True, check=True)
    return next(line for line in out.stdout.splitlines() if line.startswith("HEAVY="))


@pytest.mark.parametrize("body", [
    "import crowdbench",
    "import crowdbench.policies, crowdbench.training, crowdbench.training.methods",
    "from crowdbench.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass",
    "import crowdbench, numpy as np\nenv = crowdbench.parallel_env(num_humans=5)\nenv.reset(seed=0)\n"
    "env.step({'robot': np.zeros(2)})",
    "from crowdbench.cli import main\nassert main(['evaluate', 'orca', '--episodes', '2', '--humans', '4']) == 0\n"
    "assert main(['evaluate', '--policy', 'social_force', '--episodes', '2', '--humans', '4']) == 0\n"
    "assert main(['evaluate', '--policy', 'linear', '--episodes', '2', '--humans', '4']) == 0",
])
def test_no_torch_for_the_core_and_the_classic_baselines(body):
    assert _heavy(body) == "HEAVY="


RUN_EVERY_CHECKPOINT = """
import numpy as np
from crowdbench import checkpoints
from crowdbench.config import WorldConfig
from crowdbench.policies import METHODS, REFERENCE_METHOD, make_policy
from crowdbench.robots import make_observation
from crowdbench.worlds import CrowdWorld

policy = make_policy(REFERENCE_METHOD)
cfg = WorldConfig(num_humans=5)
world = CrowdWorld(cfg, 2, "circle_crossing", "responsive_orca")
world.reset(seeds=[0, 1])
policy.act(make_observation(policy.observation, cfg).build(world))
for name in METHODS.names():
    for ckpt in checkpoints.shipped_names(name):
        make_policy(name, checkpoint=ckpt)
print("TRAINING=" + ",".join(m for m in sys.modules if m.startswith("crowdbench.training")))
"""


def test_running_a_learned_policy_needs_neither_rsl_rl_nor_training():
    out = subprocess.run([sys.executable, "-c", PROBE.format(body=RUN_EVERY_CHECKPOINT)], capture_output=True,
                         text=True, check=True).stdout.splitlines()
    assert "HEAVY=torch" in out  # no rsl_rl, no tensordict
    assert "TRAINING=" in out  # no crowdbench.training module


def test_lazy_registry_entries_resolve_and_reject_conflicts():
    from crowdbench.registry import Registry

    reg: Registry = Registry("thing", "crowdbench.test_things")
    reg.register("od", "collections:OrderedDict")
    assert "od" in reg.names()
    from collections import OrderedDict

    reg.register("od", OrderedDict)  # the lazy entry's own object: not a conflict
    assert reg.get("od") is OrderedDict
    with pytest.raises(ValueError, match="already registered"):
        reg.register("od", "collections:Counter")
    with pytest.raises(ValueError, match="unknown thing 'x'; valid choices: od"):
        reg.get("x")


def test_shipped_checkpoints_are_package_data():
    from pathlib import Path

    from crowdbench import checkpoints

    names = checkpoints.shipped_names("h2int")
    assert {"h2int", "flat", "meanpool", "standard"} <= set(names)
    folder = Path(checkpoints.shipped("h2int", "h2int")).parent
    assert folder.relative_to(Path(__import__("crowdbench").__file__).parent)  # inside the package
    pyproject = (Path(__file__).resolve().parents[1] / "pyproject.toml").read_text()
    assert '"crowdbench.policies.h2int" = ["checkpoints/*.pt"]' in pyproject  # installed by `pip install .`


# ------------------------------------------------------------------------------------------------------------ layers
PACKAGE = Path(__file__).resolve().parents[1] / "crowdbench"
POLICY_INFRA = {"base", "method", "classic", "nets", "recurrent"}
"""Modules of :mod:`crowdbench.policies` that are not a method's (the rest of ``policies/`` are method sub-packages,
and ``recurrent_training``, the PPO bindings' shared base)."""
LAYERS: dict[str, set[str]] = {
    # unit → the crowdbench units it may import (a unit: a sub-package, or a top-level module)
    "validate": set(), "io": set(), "spatial": set(), "geometry": {"spatial"}, "progress": set(), "nn": set(),
    "registry": {"validate"},
    "config": {"validate"},
    "checkpoints": {"io", "registry"},
    "metrics": set(),
    "render": {"io"},
    "datasets": {"humans"},  # ETH/UCY validation runs the pedestrian models
    "humans": {"datasets", "geometry", "registry", "spatial", "validate"},
    "worlds": {"config", "datasets", "geometry", "humans", "registry", "spatial"},
    "robots": {"config", "registry", "worlds"},
    "predictors": {"__version__", "checkpoints", "config", "io", "nn", "registry", "robots", "worlds"},
    "policies": {"checkpoints", "config", "humans", "io", "nn", "registry", "robots"},
    "envs": {"config", "humans", "policies", "render", "robots", "worlds"},
    "evaluation": {"config", "humans", "metrics", "policies", "robots", "worlds"},
    "training": {"__version__", "checkpoints", "cli", "config", "envs", "evaluation", "humans", "io", "policies",
                 "registry", "robots", "worlds"},
    "leaderboard": {"__version__", "checkpoints", "evaluation", "io", "metrics", "policies", "validate", "worlds"},
    "cli": {"checkpoints", "config", "datasets", "envs", "evaluation", "humans", "io", "leaderboard", "policies",
            "predictors", "progress", "render", "robots", "training", "worlds"},
    "bench": {"cli"},  # the public name of crowdbench.cli.bench
    "crowdbench": {"envs"},
}
"""The allowed import graph (docs/design.md, "Layers"): the simulation (worlds, humans, robots, predictors) below
the policies, the policies below the environments, evaluation and training, the leaderboard package above them and
the applications (the cli package: commands, bench, panels) on top."""
EXCEPTIONS: dict[str, set[str]] = {
    "crowdbench.humans.learned": {"envs", "worlds"},  # the agents' observation kernel and action map (the env's)
    "crowdbench.humans.rewards": {"worlds"},  # the compiled clearance kernel
    "crowdbench.predictors.training": {"policies"},  # the ORCA robot drives while the crowd is recorded
    "crowdbench.policies.recurrent_training": {"training"},  # the PPO bindings: loaded by training only
    "crowdbench.training.seeds": {"cli"},  # one run per seed is the command line, repeated
    "crowdbench.training.ship": {"predictors"},  # shipping a trained predictor: its checkpoint folder
}
"""Module-level exceptions to :data:`LAYERS`' rules of their unit (each with its reason); a policy method's
``training.py`` (its PPO binding, named by its descriptor and loaded by training only) may import training too."""
HEAVY_OWNERS = {"rsl_rl": {"training"}, "tensordict": {"training"}}
"""Third-party libraries only these units may import."""


def _imports(path: Path) -> set[str]:
    """Every module an import statement of ``path`` names (function-local ones included)."""
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.add(node.module)
            out.update(f"{node.module}.{a.name}" for a in node.names)
    return out


def _modules() -> dict[str, Path]:
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def _unit(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "crowdbench"


def _is_binding(module: str) -> bool:
    parts = module.split(".")
    return parts[:2] == ["crowdbench", "policies"] and (parts[-1] == "training" and len(parts) == 4
                                                        or module == "crowdbench.policies.recurrent_training")


def test_layers_import_downward_only():
    bad = []
    for module, path in _modules().items():
        unit = _unit(module)
        allowed = LAYERS[unit] | EXCEPTIONS.get(module, set()) | ({"training"} if _is_binding(module) else set())
        for name in _imports(path):
            top = name.split(".")[0]
            if top == "crowdbench" and "." in name and _unit(name) != unit and _unit(name) not in allowed:
                bad.append(f"{module} imports {name}")
            if top in HEAVY_OWNERS and unit not in HEAVY_OWNERS[top]:
                bad.append(f"{module} imports {top}")
    assert not bad, "imports against the layers (tests/test_architecture.py LAYERS):\n" + "\n".join(sorted(bad))


def test_every_unit_is_placed_in_the_layers():
    assert {_unit(m) for m in _modules()} - {"__main__"} <= set(LAYERS)


def test_nothing_imports_a_ppo_binding_but_training():
    bad = [f"{m} imports {n}" for m, path in _modules().items() if _unit(m) != "training" and not _is_binding(m)
           for n in _imports(path) if _is_binding(n)]
    assert not bad


def test_the_core_names_no_method():
    """Outside ``crowdbench/policies/`` no string literal is a learned method's name, board label or shipped
    checkpoint, and no module imports a method's sub-package (the value trainer excepted: it is that family's)."""
    from crowdbench import checkpoints
    from crowdbench.policies import methods

    learned = [m for m in methods() if m.takes_checkpoint]
    names = {m.name for m in learned} | {e.label for m in learned for e in m.entries}
    names |= {n for m in learned for n in checkpoints.shipped_names(m.name)}
    subpackages = {p.name for p in (PACKAGE / "policies").iterdir() if (p / "__init__.py").exists()}
    literals, imports = [], []
    for module, path in _modules().items():
        if _unit(module) == "policies":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names:
                literals.append(f"{module}:{node.lineno} {node.value!r}")
        for name in _imports(path):
            parts = name.split(".")
            family = module == "crowdbench.training.value" and parts[2:3] == ["value"]
            if parts[:2] == ["crowdbench", "policies"] and len(parts) > 2 and parts[2] in subpackages and not family:
                imports.append(f"{module} imports {name}")
    assert not literals and not imports, literals + imports
