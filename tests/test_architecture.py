"""Architecture guarantees: heavy libraries load lazily, learned methods resolve by name, the shipped checkpoints
are package data."""

from __future__ import annotations

import subprocess
import sys

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


def test_learned_policies_load_on_first_use():
    heavy = _heavy("from crowdbench.policies import make_policy\nmake_policy('h2int')")
    assert heavy == "HEAVY=rsl_rl,tensordict,torch"


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
