"""``crowdbench`` command line: ``demo`` (one rendered episode → GIF) and ``evaluate`` (batched metrics)."""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from crowdbench.humans import HUMAN_MODELS
from crowdbench.io import write_text
from crowdbench.policies import POLICIES, make_policy
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
    p.add_argument("--policy", default="orca", help=f"robot policy, one of {POLICIES.names()}")
    p.add_argument("--seed", type=int, default=0)


def demo(args: argparse.Namespace) -> int:
    """Run one episode with the chosen robot policy, print its outcome and write an animated GIF."""
    from crowdbench.envs import CrowdParallelEnv
    from crowdbench.render import save_gif

    env = CrowdParallelEnv(layout=args.layout, num_humans=args.humans, human_model=args.human_model,
                           human_model_kwargs=_model_kwargs(args.human_model, args.responsiveness),
                           render_mode="rgb_array", observation=POLICIES.get(args.policy).observation)
    policy = make_policy(args.policy, env.config)
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
    print(f"layout={args.layout} humans={args.humans} model={args.human_model} policy={args.policy} seed={args.seed}")
    print(f"outcome={info['outcome']} time={info['time']:.2f}s path_length={path:.2f}m frames={len(frames)}")
    print(f"wrote {args.gif}")
    return 0


def evaluate(args: argparse.Namespace) -> int:
    """Batched evaluation of a registered policy; prints the paper's six metrics (optionally writes JSON)."""
    from crowdbench.evaluation import run_episodes, summarize

    policy = make_policy(args.policy)
    eps = run_episodes(policy, args.episodes, seed=args.seed, num_worlds=args.worlds, layout=args.layout,
                       num_humans=args.humans, human_model=args.human_model,
                       human_model_kwargs=_model_kwargs(args.human_model, args.responsiveness))
    summary = summarize(eps)
    for k, v in summary.items():
        print(f"{k:>15}: {v:.4f}" if isinstance(v, float) else f"{k:>15}: {v}")
    if args.json:
        result = {"args": {k: v for k, v in vars(args).items() if k != "func"}, "summary": summary}
        write_text(args.json, json.dumps(result, indent=2) + "\n")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="crowdbench", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("demo", help="run one rendered episode and write a GIF")
    _common(p)
    p.add_argument("--gif", default="demo.gif", help="output GIF path")
    p.set_defaults(func=demo)
    p = sub.add_parser("evaluate", help="batched evaluation of a robot policy")
    _common(p)
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--worlds", type=int, default=16, help="worlds stepped together")
    p.add_argument("--json", default=None, help="write the summary to this JSON file")
    p.set_defaults(func=evaluate)
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except ValueError as e:  # bad input: one clear line
        print(f"crowdbench: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
