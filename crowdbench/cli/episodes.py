"""Episodes of one policy: ``demo``/``render`` (a GIF), ``evaluate`` (batched metrics), ``tables`` (the paper's
cells for one policy) and ``panels`` (trajectories per layout)."""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

from crowdbench import checkpoints
from crowdbench.humans import HUMAN_MODELS
from crowdbench.io import write_text
from crowdbench.policies import DEFAULT_POLICY, POLICIES, REFERENCE_METHOD, make_policy, method_of, methods
from crowdbench.worlds import LAYOUTS


def _model_kwargs(model: str, responsiveness: float | None) -> dict:
    if responsiveness is None:
        return {}
    if model != "responsive_orca":
        raise SystemExit(f"--responsiveness applies to --human-model responsive_orca, not {model!r}")
    return {"responsiveness": responsiveness}


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--layout", default="circle_crossing", choices=LAYOUTS.names())
    p.add_argument("--humans", type=int, default=20, help="number of pedestrians")
    p.add_argument("--human-model", default="responsive_orca", help=f"one of {HUMAN_MODELS.names()}")
    p.add_argument("--responsiveness", type=float, default=None, help="crowd mean ρ for responsive_orca")
    p.add_argument("--policy", default=None, help=f"robot policy (default {DEFAULT_POLICY}), one of {POLICIES.names()}")
    p.add_argument("--seed", type=int, default=0)


def demo(args: argparse.Namespace) -> int:
    """Run one episode with the chosen robot policy, print its outcome and write an animated GIF."""
    from crowdbench.config import make_config
    from crowdbench.envs import CrowdParallelEnv
    from crowdbench.render import save_gif

    name = getattr(args, "policy_pos", None) or args.policy or DEFAULT_POLICY
    kwargs = {"layout": args.layout, "num_humans": args.humans, "human_model": args.human_model,
              "human_model_kwargs": _model_kwargs(args.human_model, args.responsiveness), "render_mode": "rgb_array"}
    args.policy, args.policy_pos = name, None
    policy = _policy(args, make_config(num_humans=args.humans))  # the env's config (envs.common.build_world)
    # the instance's observation: a checkpoint may choose it (DS-RNN's slot order)
    env = CrowdParallelEnv(**kwargs, observation=policy.observation, observation_kwargs=policy.observation_kwargs)
    obs, _ = env.reset(seed=args.seed)
    frames = [env.render()]
    path, info = 0.0, {}
    while env.agents:
        start = env.world.pos[0, 0].copy()
        action = policy.act({k: v[None] for k, v in obs["robot"].items()})[0]
        obs, _, _, _, infos = env.step({"robot": action})
        info = infos["robot"]
        path += float(np.linalg.norm(env.world.pos[0, 0] - start))
        frames.append(env.render())
    save_gif(frames, args.gif)
    if getattr(args, "png", None):  # a still of the episode's middle (the README picture)
        from PIL import Image

        from crowdbench.io import atomic_path

        with atomic_path(args.png, suffix=".png") as tmp:
            Image.fromarray(frames[len(frames) // 2]).save(tmp, format="PNG")
        print(f"wrote {args.png}")
    print(f"layout={args.layout} humans={args.humans} model={args.human_model} policy={args.policy} seed={args.seed}")
    print(f"outcome={info['outcome']} time={info['time']:.2f}s path_length={path:.2f}m frames={len(frames)}")
    print(f"wrote {args.gif}")
    return 0


def _policy(args: argparse.Namespace, config=None):
    """The policy named positionally or by ``--policy`` (with ``--checkpoint`` for checkpoint-backed ones)."""
    import inspect

    name = args.policy_pos or args.policy
    if args.policy_pos and args.policy not in (None, args.policy_pos):
        raise ValueError(f"policy given twice ({args.policy_pos!r} and --policy {args.policy!r}); give one")
    name = name or DEFAULT_POLICY
    factory = POLICIES.get(name)
    params = inspect.signature(factory).parameters
    if args.checkpoint and "checkpoint" not in params:
        raise ValueError(f"--checkpoint: policy {name!r} takes no checkpoint; checkpoint-backed policies: "
                         + ", ".join(checkpoint_policies()))
    kwargs = {"checkpoint": args.checkpoint} if args.checkpoint else {}
    sensing = getattr(args, "sensing", None)
    if sensing is not None and "sensing" in params:
        kwargs["sensing"] = sensing
    policy = make_policy(name, config, **kwargs)
    if sensing is not None and policy.sensing != sensing:
        raise ValueError(f"--sensing {sensing}: policy {name!r} senses at tier {policy.sensing!r} and has no "
                         "sensing option; valid choices: omit --sensing, or a policy with a sensing option "
                         f"({', '.join(sensing_policies())})")
    return policy


def checkpoint_policies() -> list[str]:
    """Registered methods whose policy loads a checkpoint (listed in errors; any policy with a ``checkpoint``
    argument accepts one)."""
    return [m.name for m in methods() if m.takes_checkpoint]


def sensing_policies() -> list[str]:
    """Registered methods whose policy runs at several sensing tiers (``--sensing``)."""
    return [m.name for m in methods() if len(m.sensing) > 1]


def evaluate(args: argparse.Namespace) -> int:
    """Batched evaluation of a registered policy; prints the paper's six metrics (optionally writes JSON)."""
    from crowdbench.evaluation import run_episodes, summarize
    from crowdbench.progress import Progress

    policy = _policy(args)
    bar = Progress(args.episodes, "episodes")
    eps = run_episodes(policy, args.episodes, seed=args.seed, num_worlds=args.worlds, layout=args.layout,
                       num_humans=args.humans, human_model=args.human_model,
                       human_model_kwargs=_model_kwargs(args.human_model, args.responsiveness),
                       counterfactual=args.pedestrian_delay, progress=bar.update, sensing=args.sensing)
    bar.close()
    summary = summarize(eps)
    for k, v in summary.items():
        if k == "ci":
            continue
        lo, hi = summary["ci"].get(k, (None, None))
        ci = f"   95 % CI [{lo:.4f}, {hi:.4f}]" if lo is not None and np.isfinite(lo) else ""
        print(f"{k:>18}: {v:.4f}{ci}" if isinstance(v, float) else f"{k:>18}: {v}")
    if args.json:
        result = {"args": {k: v for k, v in vars(args).items() if k != "func"}, "summary": summary}
        write_text(args.json, json.dumps(result, indent=2) + "\n")
    return 0


def tables_cmd(args: argparse.Namespace) -> int:
    """Regenerate the paper's Table I/II/III cells for one policy."""
    import torch

    from crowdbench import leaderboard

    torch.set_num_threads(1)
    grid = leaderboard.grid(tuple(t.strip() for t in args.tables.split(",")))
    kwargs = {"checkpoint": args.checkpoint} if args.checkpoint else {}
    label = _entry_label(args.policy, args.checkpoint)
    results = leaderboard.evaluate_cells(args.policy, grid, args.episodes, args.seed, policy_kwargs=kwargs,
                                         label=label)
    meta = {"command": "crowdbench " + " ".join(sys.argv[1:]), "policy": args.policy, "checkpoint": args.checkpoint,
            "episodes": args.episodes, "seed": args.seed}
    leaderboard.save(results, args.json, args.md, meta)
    print(leaderboard.markdown(results))
    return 0


def _entry_label(policy: str, checkpoint: str | None) -> str:
    """The label of the leaderboard row that runs ``policy`` on ``checkpoint`` (a shipped name or path; ``None``: the
    policy's default), else the policy's name."""
    from crowdbench import leaderboard

    method = method_of(policy) if policy in [m.name for m in methods()] else None
    if method is None or not method.takes_checkpoint:
        return policy
    path = os.path.realpath(checkpoints.resolve(policy, checkpoint))
    for e in leaderboard.method_entries():
        ckpt = e.policy_kwargs().get("checkpoint")
        if e.policy == policy and ckpt and os.path.realpath(checkpoints.resolve(policy, ckpt)) == path:
            return e.label
    return policy


def panels_cmd(args: argparse.Namespace) -> int:
    """One episode per layout, trajectories drawn (the paper's Fig. 4)."""
    from crowdbench.cli.panels import plot

    name = args.policy_pos or args.policy or REFERENCE_METHOD
    print(f"wrote {plot(name, args.out, args.humans, args.seed, args.responsiveness, args.checkpoint)}")
    return 0


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """The sub-commands of this module."""
    p = sub.add_parser("demo", help="run one rendered episode and write a GIF")
    _common(p)
    p.add_argument("--checkpoint", default=None, help="checkpoint of a checkpoint-backed policy")
    p.add_argument("--gif", default="demo.gif", help="output GIF path")
    p.add_argument("--png", default=None, help="also write the episode's middle frame as a PNG (docs/demo.png: "
                                               "`crowdbench demo --policy h2int --responsiveness 0.5 --gif "
                                               "docs/demo.gif --png docs/demo.png`)")
    p.set_defaults(func=demo)
    p = sub.add_parser("render", help="one episode of any policy as an animated GIF (same as demo, policy first)")
    _common(p)
    p.add_argument("policy_pos", nargs="?", default=None, metavar="POLICY", help="robot policy (same as --policy)")
    p.add_argument("--checkpoint", default=None, help="checkpoint of a checkpoint-backed policy")
    p.add_argument("--out", dest="gif", default="episode.gif", help="output GIF path")
    p.set_defaults(func=demo)
    p = sub.add_parser("evaluate", help="batched evaluation of a robot policy")
    _common(p)
    p.add_argument("policy_pos", nargs="?", default=None, metavar="POLICY",
                   help="robot policy (same as --policy)")
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--worlds", type=int, default=16, help="worlds stepped together")
    p.add_argument("--json", default=None, help="write the summary to this JSON file")
    p.add_argument("--pedestrian-delay", action="store_true",
                   help="also run each episode without the robot (same seed) to measure the delay it imposes on "
                        "pedestrians (doubles the crowd simulation)")
    p.add_argument("--checkpoint", default=None,
                   help="checkpoint of a checkpoint-backed policy: a path or a shipped name (`leaderboard list`)")
    p.add_argument("--sensing", default=None, choices=("positions", "velocities", "full"),
                   help="sensing tier (default: the policy's own — positions for every board method, as on the "
                        f"board); policies that read pedestrian states ({', '.join(sensing_policies())}) take any")
    p.set_defaults(func=evaluate)
    p = sub.add_parser("tables", help="the paper's Table I/II/III cells for one policy")
    p.add_argument("--policy", default=REFERENCE_METHOD, help=f"one of {POLICIES.names()}")
    p.add_argument("--checkpoint", default=None)
    p.add_argument("--tables", default="I,II,III", help="comma-separated subset of I, II, III")
    p.add_argument("--episodes", type=int, default=500)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", default=None)
    p.add_argument("--md", default=None)
    p.set_defaults(func=tables_cmd)
    p = sub.add_parser("panels", help="trajectory panels of one episode per layout (the paper's Fig. 4)")
    p.add_argument("policy_pos", nargs="?", default=None, metavar="POLICY")
    p.add_argument("--policy", default=None)
    p.add_argument("--checkpoint", default=None)
    p.add_argument("--humans", type=int, default=20)
    p.add_argument("--responsiveness", type=float, default=0.5)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default="trajectories.png")
    p.set_defaults(func=panels_cmd)
