"""End-to-end check of crowdbench's multi-agent env under TorchRL's PettingZoo wrapper.

    python3 -m venv /tmp/trl && . /tmp/trl/bin/activate && pip install torch==2.13.0 torchrl==0.14.1
    pip install -e . && python scripts/check_torchrl.py

(A venv of its own: torchrl 0.14 pins tensordict 0.14, rsl-rl's own install uses 0.15.) Wraps
``crowdbench.parallel_env(num_humans=6, robot=None, flat_observations=True)`` as one agent group, runs TorchRL's
``check_env_specs`` and a 50-step random rollout, and prints the shapes.
"""

from __future__ import annotations

import crowdbench


def main() -> None:
    from torchrl.envs.libs.pettingzoo import PettingZooWrapper
    from torchrl.envs.utils import check_env_specs

    agents = [f"human_{i}" for i in range(6)]
    env = PettingZooWrapper(env=crowdbench.parallel_env(num_humans=6, robot=None, flat_observations=True),
                            use_mask=True, categorical_actions=False, group_map={"pedestrians": agents})
    check_env_specs(env)
    td = env.rollout(50)
    rewards = tuple(td["next", "pedestrians", "reward"].shape)
    print(f"check_env_specs passed; rollout {tuple(td.batch_size)}, rewards {rewards}")


if __name__ == "__main__":
    main()
