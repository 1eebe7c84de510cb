"""``crowdbench`` command line: ``demo`` (one rendered episode → GIF) and ``evaluate`` (batched metrics)."""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

from crowdbench import checkpoints
from crowdbench.humans import HUMAN_MODELS
from crowdbench.io import write_text
from crowdbench.policies import DEFAULT_POLICY, POLICIES, REFERENCE_METHOD, make_policy, method_of, methods, trained_by
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


NEW_RUN_ONLY = ("envs", "epochs", "mini_batches", "reward_scale", "learning_rate", "schedule")
"""``crowdbench train`` options of a PPO run's schedule: set on a new run, refused on a resumed one (with
``--anneal``/``--no-anneal``, ``--variant``, ``--model``)."""


def train_cmd(args: argparse.Namespace) -> int:
    """Train a PPO method with rsl-rl (a value method: :func:`train_value_cmd`); checkpoints, curve and logs go to
    ``--out``."""
    if args.seeds:
        return train_seeds_cmd(args)
    value_methods = trained_by("value")
    if args.algo in value_methods:
        return train_value_cmd(args)
    from crowdbench.training.config import RESUMABLE, TrainConfig
    from crowdbench.training.methods import PPO_METHODS
    from crowdbench.training.trainer import check_start, resume_config, train

    if args.algo not in PPO_METHODS.names():
        raise ValueError(f"train: unknown method {args.algo!r}; valid choices: "
                         f"{', '.join([*PPO_METHODS.names(), *value_methods])}")
    misplaced = [f"--{k.replace('_', '-')}" for k in VALUE_ONLY if getattr(args, k) is not None]
    if misplaced:
        raise ValueError(f"{', '.join(misplaced)}: options of the value-based methods ({', '.join(value_methods)}), "
                         f"not of {args.algo}")
    method = PPO_METHODS.get(args.algo)()
    speed = {name: getattr(args, name) for name in RESUMABLE if getattr(args, name) is not None}
    check_start(args.resume, args.init)  # before the resumed checkpoint is read
    if args.resume:  # a resumed run keeps its configuration; only its budget and speed settings may change
        if args.variant is not None or args.model:
            raise ValueError("--variant/--model: a resumed run keeps its architecture; drop them with --resume")
        fixed = [f"--{k.replace('_', '-')}" for k in NEW_RUN_ONLY if getattr(args, k) is not None]
        fixed += [] if args.anneal is None else ["--anneal" if args.anneal else "--no-anneal"]
        if fixed:
            raise ValueError(f"{', '.join(fixed)}: a resumed run keeps its configuration; drop them with --resume "
                             f"(only {', '.join('--' + k.replace('_', '-') for k in RESUMABLE)} may change)")
        path = checkpoints.run_checkpoint(args.resume)
        cfg = resume_config(path, **speed)
        out = args.out or os.path.dirname(os.path.abspath(path))
    else:
        model = {**method.variant_model(args.variant), **method.model_overrides(args.model or [])}
        overrides = {"model": model, "seed": args.seed, **speed}
        if args.anneal is not None:
            overrides["anneal"] = args.anneal
        for name in NEW_RUN_ONLY:
            if getattr(args, name) is not None:
                overrides["num_envs" if name == "envs" else name] = getattr(args, name)
        cfg = TrainConfig.for_method(args.algo, **overrides)
        out = args.out or os.path.join("runs", f"{method.label(cfg.model)}-seed{cfg.seed}")
    print(f"training {cfg.method} ({method.label(cfg.model)}) seed={cfg.seed} → {out}")
    trainer = train(cfg, out, resume=args.resume, init=args.init)
    print(f"wrote {os.path.join(out, 'last.pt')} and {os.path.join(out, 'curve.png')} "
          f"({trainer.iteration} iterations, {trainer.env_steps:,} env steps, {trainer.elapsed / 60:.1f} min)")
    return 0


def train_seeds_cmd(args: argparse.Namespace) -> int:
    """``--seeds 0,1,2``: one run per seed (:mod:`crowdbench.training.seeds`), under ``OUT/seedS``."""
    from crowdbench.training.seeds import run_seeds, seed_commands

    try:
        seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
    except ValueError:
        raise ValueError(f"--seeds {args.seeds!r}; valid choices: comma-separated integers, e.g. 0,1,2") from None
    if not seeds or len(set(seeds)) != len(seeds) or args.resume or args.init:
        raise ValueError(f"--seeds {args.seeds!r}: distinct integers, for new runs (not with --resume/--init)")
    out = args.out or os.path.join("runs", f"{args.algo}-seeds")
    commands = seed_commands(args.argv, seeds, out)
    codes = run_seeds(commands, args.backend, args.seed_workers, args.ray_address)
    for s, code in zip(seeds, codes, strict=True):
        print(f"seed {s}: {'done' if code == 0 else f'exit {code}'} → {os.path.join(out, f'seed{s}')}")
    return max(codes)


VALUE_ONLY = ("worlds", "il_episodes", "rl_episodes", "free_space", "sensing")


def train_value_cmd(args: argparse.Namespace) -> int:
    """CADRL / SARL: imitation of the ORCA robot, then TD learning (:mod:`crowdbench.training.value`)."""
    from crowdbench.training.value import ValueTrainConfig, resume_config, train_value

    ppo_only = [f"--{k.replace('_', '-')}" for k in ("variant", "model", "init", "iterations", "until_success",
                                                     "env_processes", *NEW_RUN_ONLY)
                if getattr(args, k) is not None] + ([] if args.anneal is None else ["--anneal/--no-anneal"])
    if ppo_only:
        raise ValueError(f"{', '.join(ppo_only)}: options of the PPO methods, not of {args.algo}")
    speed = {k: getattr(args, k) for k in ("minutes", "threads") if getattr(args, k) is not None}
    if args.resume:
        path = checkpoints.run_checkpoint(args.resume)
        cfg = resume_config(path, **speed)
        if cfg.method != args.algo:
            raise ValueError(f"--resume: {path!r} is a {cfg.method} run, not {args.algo}")
        out = args.out or os.path.dirname(os.path.abspath(path))
    else:
        fields = {k: getattr(args, k) for k in VALUE_ONLY if getattr(args, k) is not None}
        cfg = ValueTrainConfig(method=args.algo, seed=args.seed, **fields, **speed)
        out = args.out or os.path.join("runs", f"{args.algo}-seed{cfg.seed}")
    print(f"training {cfg.method} seed={cfg.seed} → {out}")
    trainer = train_value(cfg, out, resume=args.resume)
    print(f"wrote {os.path.join(out, 'policy.pt')}, last.pt and curve.png ({trainer.phase}: "
          f"{trainer.episode} episodes, {trainer.elapsed / 60:.1f} min)")
    return 0


def predictor_cmd(args: argparse.Namespace) -> int:
    """Record crowd trajectories, train the learned predictor, or compare predictors (ADE / FDE)."""
    from crowdbench.predictors import training as pt

    if args.action == "record":
        out = args.out or "runs/gst-data.npz"
        cfg = pt.RecordConfig(worlds=args.worlds, steps=args.steps, stride=args.stride, seed=args.seed)
        data = pt.record(cfg, out)
        print(f"wrote {out}: {len(data['pos']):,} scenes, {int(data['valid'].sum()):,} scored pedestrians")
        return 0
    if args.data is None:
        raise ValueError(f"predictor {args.action}: --data is required (a file written by `crowdbench predictor "
                         "record`)")
    data = pt.load_data(args.data)
    if args.action == "train":
        tcfg = pt.PredictorTrainConfig(epochs=args.epochs, seed=args.seed)
        out = args.out or "runs/gst"
        m = pt.train(data, out, tcfg)
        print(f"wrote {os.path.join(out, 'gst.pt')}: held-out ADE {m['ade']:.3f} m, FDE {m['fde']:.3f} m "
              f"(constant velocity {m['const_vel_ade']:.3f} / {m['const_vel_fde']:.3f} m)")
        return 0
    rows = pt.compare(data, args.checkpoint)
    for name, (ade, fde) in rows.items():
        print(f"{name:>10}: ADE {ade:.3f} m, FDE {fde:.3f} m")
    if args.json:
        write_text(args.json, json.dumps({k: {"ade": a, "fde": f} for k, (a, f) in rows.items()}, indent=1) + "\n")
    return 0


def export_cmd(args: argparse.Namespace) -> int:
    """Export a checkpoint to TorchScript and ONNX (recurrent: hidden state in and out)."""
    import importlib

    method = method_of(args.method)
    if method.export is None:
        names = ", ".join(m.name for m in methods() if m.export)
        raise ValueError(f"export --method {method.name}: it has no exporter; valid choices: {names}")
    exporter = importlib.import_module(method.export)
    os.makedirs(args.out, exist_ok=True)
    ts = exporter.export_torchscript(args.checkpoint, os.path.join(args.out, "policy.pt"))
    onnx = exporter.export_onnx(args.checkpoint, os.path.join(args.out, "policy.onnx"))
    print(f"wrote {ts} and {onnx}")
    return 0


def ship_cmd(args: argparse.Namespace) -> int:
    """A run's resumable state → the weights-only checkpoint that ships (:mod:`crowdbench.training.ship`)."""
    from crowdbench.training.ship import ship

    print(ship(args.run, args.name, method=args.method, out=args.out).line())
    return 0


def plot_cmd(args: argparse.Namespace) -> int:
    """Plot success trends of several `crowdbench tables` result files."""
    from crowdbench.leaderboard import plot_trends

    plot_trends(args.results, args.out)
    print(f"wrote {args.out}")
    return 0


def curves_cmd(args: argparse.Namespace) -> int:
    """Compare training runs (history.json files) on one figure."""
    from crowdbench.training.plots import plot_evals, plot_runs, runs_table

    if args.evals:  # the bar line at --table's bar when one is given
        plot_evals(args.histories, args.out, *([] if args.table is None else [args.table]))
    else:
        plot_runs(args.histories, args.out)
    print(f"wrote {args.out}")
    if args.table is not None:
        print(runs_table(args.histories, args.table))
    return 0


def panels_cmd(args: argparse.Namespace) -> int:
    """One episode per layout, trajectories drawn (the paper's Fig. 4)."""
    from crowdbench.panels import plot

    name = args.policy_pos or args.policy or REFERENCE_METHOD
    print(f"wrote {plot(name, args.out, args.humans, args.seed, args.responsiveness, args.checkpoint)}")
    return 0


def crowd_validate_cmd(args: argparse.Namespace) -> int:
    """Pedestrian models against the recorded ETH/UCY people (:mod:`crowdbench.datasets.validate`)."""
    from crowdbench.datasets import validate as cv

    models = [m.strip() for m in args.models.split(",") if m.strip()]
    scenes = [s.strip() for s in args.scenes.split(",") if s.strip()] if args.scenes else list(cv.SCENES)
    result = cv.validate(models, scenes)
    print(cv.markdown(result))
    if args.json:
        write_text(args.json, json.dumps(result, indent=2) + "\n")
    return 0


def train_crowd_cmd(args: argparse.Namespace) -> int:
    """Train the shared pedestrian policy (:mod:`crowdbench.training.crowd`) → ``OUT/learned_crowd.pt``."""
    from crowdbench.training.crowd import CrowdTrainConfig, train

    cfg = CrowdTrainConfig(seed=args.seed, worlds=args.worlds, iterations=args.iterations, threads=args.threads)
    train(cfg, args.out)
    print(f"wrote {os.path.join(args.out, 'learned_crowd.pt')} and history.json")
    return 0


def crowd_stats_cmd(args: argparse.Namespace) -> int:
    """Goal arrivals and contacts of pedestrian models in robot-free episodes (:mod:`crowdbench.humans.crowd_stats`)."""
    from crowdbench.humans.crowd_stats import crowd_stats

    rows = [crowd_stats(m.strip(), range(args.seed, args.seed + args.episodes), args.humans, args.max_cycles)
            for m in args.models.split(",") if m.strip()]
    print("| model | episodes | arrivals / episode | contact steps / episode | collisions / ped-min | time to goal "
          "[s] | irregularity [rad/step] | speed p50 / p95 [m/s] |\n|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['model']} | {r['episodes']} | {r['arrivals_per_episode']:.1f} | "
              f"{r['contact_steps_per_episode']:.1f} | {r['collisions_per_ped_minute']:.3f} | "
              f"{r['time_to_goal_s']:.1f} | {r['path_irregularity_rad']:.3f} | {r['speed_p50']:.2f} / "
              f"{r['speed_p95']:.2f} |")
    if args.json:
        write_text(args.json, json.dumps(rows, indent=2) + "\n")
    return 0


def paper_cmd(args: argparse.Namespace) -> int:
    """Every stored board cell beside the paper's number (:mod:`crowdbench.paper`); reads cells, runs nothing."""
    from crowdbench import paper

    print(paper.report(args.out, args.md))
    return 0


def bench_cmd(args: argparse.Namespace) -> int:
    """Measure and print the throughput figures; write benchmarks/RESULTS.md and the throughput PNG."""
    from crowdbench.bench import main as bench_main

    bench_main(quick=args.quick, json_path=args.json, out_dir=args.out)
    return 0


def tables_cmd(args: argparse.Namespace) -> int:
    """Regenerate the paper's Table I/II/III cells for one policy."""
    import torch

    from crowdbench import leaderboard

    torch.set_num_threads(1)
    grid = leaderboard.cells(tuple(t.strip() for t in args.tables.split(",")))
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


def _methods(spec: str | None, add: list[str]) -> list:
    """Leaderboard entries from ``--methods`` (shipped entry names, registered policy names or LABEL=POLICY[@CKPT],
    comma-separated; default: every shipped entry) and ``--add``."""
    from crowdbench import leaderboard

    entries = leaderboard.board_entries()
    if not spec:
        chosen = list(entries.values())
    else:
        chosen = []
        for item in (s.strip() for s in spec.split(",") if s.strip()):
            if item in entries:
                chosen.append(entries[item])
            elif "=" in item:
                chosen.append(leaderboard.parse_entry(item))
            elif item in leaderboard.STALE:
                raise ValueError(f"--methods {item}: {leaderboard.STALE[item]}. To score a checkpoint anyway, name it: "
                                 f"--add LABEL={item}@PATH")
            elif item in POLICIES.names():
                chosen.append(leaderboard.Entry(item, item))
            else:
                raise ValueError(f"--methods: unknown {item!r}; valid choices: {', '.join(entries)}, "
                                 f"a registered policy ({', '.join(POLICIES.names())}) or LABEL=POLICY[@CHECKPOINT]")
    return chosen + [leaderboard.parse_entry(a) for a in add]


def leaderboard_run_cmd(args: argparse.Namespace) -> int:
    """A suite for every chosen method → ``OUT/<method>.json|md``, ``OUT/cells/`` and ``OUT/LEADERBOARD.md``."""
    from crowdbench import harness

    suite = harness.load_suite(args.suite, episodes=args.episodes)
    entries = _methods(args.methods, args.add)
    out = args.out or ("leaderboards" if args.suite == "paper" and args.episodes is None
                       else os.path.join("runs", f"leaderboard-{suite.name}"))
    harness.run(suite, entries, out, workers=args.workers, backend=args.backend, ray_address=args.ray_address,
                force=args.force, progress=harness.print_progress)
    with open(os.path.join(out, "LEADERBOARD.md")) as f:
        print(f.read())
    return 0


def leaderboard_list_cmd(args: argparse.Namespace) -> int:
    """The shipped leaderboard entries, every registered policy with its shipped checkpoints, and the suites."""
    from crowdbench import harness, leaderboard

    print("leaderboard entries (crowdbench leaderboard run --methods NAME,...):")
    for slug, e in leaderboard.board_entries().items():
        ckpt = e.policy_kwargs().get("checkpoint")
        where = f"  checkpoint {os.path.relpath(checkpoints.resolve(e.policy, ckpt))}" if ckpt else ""
        tier = f"sensing={leaderboard.entry_sensing(e)}"
        print(f"  {slug:<22} policy {e.policy:<14} group {e.group:<14} {tier:<19}{where}")
    for label, why in leaderboard.STALE.items():
        print(f"  {label:<22} not on the board: {why}")
    print("registered robot policies (built-in and entry-point plug-ins; any can run with --methods NAME):")
    for name in POLICIES.names():
        names = checkpoints.shipped_names(name)
        print(f"  {name:<22} shipped checkpoints: {', '.join(names) if names else '—'}")
    print("suites (--suite NAME or a path to a .toml file):")
    for name in harness.suite_names():
        s = harness.load_suite(name)
        print(f"  {name:<10} {len(s.grid()):>2} cells × {s.episodes} episodes, seed {s.seed} — {s.description}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="crowdbench", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("demo", help="run one rendered episode and write a GIF")
    _common(p)
    p.add_argument("--checkpoint", default=None, help="checkpoint of a checkpoint-backed policy")
    p.add_argument("--gif", default="demo.gif", help="output GIF path")
    p.add_argument("--png", default=None, help="also write the episode's middle frame as a PNG (docs/demo.png: "
                                               "`crowdbench demo --responsiveness 0.5 --gif docs/demo.gif --png "
                                               "docs/demo.png`)")
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
    p = sub.add_parser("train", help="train a learned method: rsl-rl PPO or value learning (its `trainer`)")
    p.add_argument("algo", metavar="METHOD",
                   help=f"a method crowdbench trains: {', '.join([*trained_by('ppo'), *trained_by('value')])}")
    p.add_argument("--variant", default=None, help="a named architecture of the method (its PPO binding's variants; "
                        "default: its default variant)")
    p.add_argument("--model", action="append", default=None, metavar="FIELD=VALUE",
                   help="architecture field over the variant's (repeatable), e.g. --model d_model=64 --model "
                        "gru_hidden=128; the fields are the method's architecture config")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--seeds", default=None, metavar="S,S,...",
                   help="train several seeds, each a run of its own under OUT/seedS, in parallel processes "
                        "(--backend local) or as Ray tasks (--backend ray); equal to training them one by one")
    p.add_argument("--backend", default="local", choices=("local", "ray"), help="with --seeds (default local)")
    p.add_argument("--seed-workers", type=int, default=None, help="with --seeds --backend local: processes "
                                                                  "(default one per seed, at most the cores)")
    p.add_argument("--ray-address", default=None, help="with --seeds --backend ray: an existing cluster")
    p.add_argument("--out", default=None, help="run folder (default runs/VARIANT-seedS)")
    p.add_argument("--resume", default=None, help="run folder or checkpoint to continue exactly")
    p.add_argument("--init", default=None, metavar="CHECKPOINT",
                   help="start a new run from this run's network weights (same architecture; the noise fields "
                        "action_std/learn_std, schedule, optimiser and counters are the new run's): fine-tuning")
    p.add_argument("--iterations", type=int, default=None, help="stop after this many PPO iterations in total")
    p.add_argument("--minutes", type=float, default=None, help="wall-clock budget in minutes")
    p.add_argument("--until-success", type=float, default=None,
                   help="stop once a quick evaluation (every 20 iterations: N=20, ρ=0.5) reaches this success rate")
    p.add_argument("--envs", type=int, default=None, help="worlds stepped together (default 256)")
    p.add_argument("--threads", type=int, default=None,
                   help="CPU threads for the network, data-parallel over samples (default 2)")
    p.add_argument("--env-processes", type=int, default=None,
                   help="processes stepping the worlds (default 2; results are identical for any value)")
    p.add_argument("--epochs", type=int, default=None,
                   help="PPO epochs per iteration (default 4; fewer run faster but learned less per step: "
                        "studies/crowdbench-0.2/schedule-study)")
    p.add_argument("--mini-batches", type=int, default=None, help="PPO mini-batches per epoch (default 4)")
    p.add_argument("--reward-scale", type=float, default=None,
                   help="factor on the rewards PPO sees (default 0.1; 1 = the originals' unscaled rewards)")
    p.add_argument("--learning-rate", type=float, default=None,
                   help="initial Adam learning rate (default: the method's recipe)")
    p.add_argument("--schedule", default=None, choices=("adaptive", "fixed"),
                   help="learning-rate schedule: adaptive (rsl-rl's KL-target rule) or fixed (default: the "
                        "method's recipe)")
    p.add_argument("--anneal", action=argparse.BooleanOptionalAction, default=None,
                   help="the responsiveness curriculum (ρ annealed from 0.8 to 0; the reference method's default) "
                        "or, with --no-anneal, training at the final ρ = 0 from the start (the CrowdNav++ "
                        "baselines' default, the originals' invisible robot)")
    p.add_argument("--worlds", type=int, default=None,
                   help="value methods: episodes run at once (default 10; same episode and update counts)")
    p.add_argument("--il-episodes", type=int, default=None, help="value methods: ORCA demonstrations (default 3000)")
    p.add_argument("--rl-episodes", type=int, default=None, help="value methods: TD-learning episodes (default 10000)")
    p.add_argument("--sensing", default=None, choices=("positions", "velocities", "full"),
                   help="value methods: sensing tier trained at (default positions: velocities estimated from "
                        "positions)")
    p.add_argument("--free-space", action=argparse.BooleanOptionalAction, default=None,
                   help="value methods: value states with nobody sensed analytically (default off: it made CADRL "
                        "worse, README)")
    p.set_defaults(func=train_cmd)
    p = sub.add_parser("predictor", help="trajectory predictor (of the predicted observation): record crowd data, "
                                         "train, compare")
    p.add_argument("action", choices=("record", "train", "compare"))
    p.add_argument("--out", default=None, help="record: the .npz to write; train: the run folder (gst.pt)")
    p.add_argument("--data", default=None, help="train/compare: scenes written by `predictor record`")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--worlds", type=int, default=32, help="record: worlds stepped at once")
    p.add_argument("--steps", type=int, default=2000, help="record: steps per world")
    p.add_argument("--stride", type=int, default=4, help="record: steps between recorded scenes")
    p.add_argument("--epochs", type=int, default=15, help="train: passes over the scenes")
    p.add_argument("--checkpoint", default=None, help="compare: the gst checkpoint (default: the shipped one)")
    p.add_argument("--json", default=None, help="compare: also write the errors to this JSON file")
    p.set_defaults(func=predictor_cmd)
    p = sub.add_parser("export", help="export a checkpoint to TorchScript and ONNX")
    p.add_argument("--method", default=REFERENCE_METHOD,
                   help=f"the method whose checkpoint is exported (default {REFERENCE_METHOD})")
    p.add_argument("--checkpoint", default=None, help="checkpoint (path or shipped name; default: the method's own)")
    p.add_argument("--out", default="export")
    p.set_defaults(func=export_cmd)
    p = sub.add_parser("ship", help="write a run's weights-only checkpoint (weights, config, provenance) into the "
                                    "method's shipped checkpoints; no optimiser, RNG, memory or history")
    p.add_argument("run", metavar="RUN_OR_CHECKPOINT", help="run folder (its last.pt) or checkpoint file")
    p.add_argument("--name", default=None, help="shipped name: <method's checkpoints folder>/NAME.pt, e.g. "
                                                "METHOD-seed1 (required unless --out)")
    p.add_argument("--method", default=None, help="the method the checkpoint must hold (default: what it holds)")
    p.add_argument("--out", default=None, help="write this file instead of the method's folder")
    p.set_defaults(func=ship_cmd)
    p = sub.add_parser("tables", help="the paper's Table I/II/III cells for one policy")
    p.add_argument("--policy", default=REFERENCE_METHOD, help=f"one of {POLICIES.names()}")
    p.add_argument("--checkpoint", default=None)
    p.add_argument("--tables", default="I,II,III", help="comma-separated subset of I, II, III")
    p.add_argument("--episodes", type=int, default=500)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", default=None)
    p.add_argument("--md", default=None)
    p.set_defaults(func=tables_cmd)
    p = sub.add_parser("leaderboard", help="score methods on a suite (run) or list methods and suites (list)")
    lsub = p.add_subparsers(dest="action", required=True)
    q = lsub.add_parser("run", help="evaluate methods on a suite; finished cells are stored as they finish")
    q.add_argument("--suite", default="paper", help="paper (Tables I–III, 500 episodes), quick, or a .toml path")
    q.add_argument("--methods", default=None,
                   help="comma-separated: shipped entries, registered policies or LABEL=POLICY[@CHECKPOINT] "
                        "(default: every shipped entry)")
    q.add_argument("--add", action="append", default=[], metavar="LABEL=POLICY[@CHECKPOINT]",
                   help="an extra row (repeatable)")
    q.add_argument("--episodes", type=int, default=None, help="override the suite's episodes per cell")
    q.add_argument("--workers", type=int, default=1, help="cells evaluated in parallel (processes or Ray tasks)")
    q.add_argument("--backend", default="local", help="local (this machine) or ray (crowdbench[ray])")
    q.add_argument("--ray-address", default=None, help="an existing Ray cluster (default: a local Ray instance)")
    q.add_argument("--out", default=None,
                   help="results folder (default: leaderboards for the paper suite, else runs/leaderboard-SUITE)")
    q.add_argument("--force", action="store_true", help="re-evaluate stored cells too")
    q.set_defaults(func=leaderboard_run_cmd)
    q = lsub.add_parser("paper", help="every stored cell beside the paper's Tables I–III (reads cells only)")
    q.add_argument("--out", default="leaderboards", help="the leaderboard folder (default leaderboards)")
    q.add_argument("--md", default=None, help="markdown file to write (default OUT/PAPER.md)")
    q.set_defaults(func=paper_cmd)
    q = lsub.add_parser("list", help="shipped entries, registered policies with checkpoints, suites")
    q.set_defaults(func=leaderboard_list_cmd)
    p = sub.add_parser("crowd-validate", help="ADE/FDE of pedestrian models against the recorded ETH/UCY people")
    p.add_argument("--models", default="const_vel,orca,social_force,responsive_orca",
                   help="comma-separated: const_vel and any pedestrian model (default: %(default)s)")
    p.add_argument("--scenes", default=None, help="comma-separated subset of eth,hotel,univ,zara1,zara2 (default all)")
    p.add_argument("--json", default=None, help="write {scene: {model: {ade, fde, samples}}} to this file")
    p.set_defaults(func=crowd_validate_cmd)
    p = sub.add_parser("train-crowd", help="train the learned_crowd pedestrian policy (rsl-rl PPO, every pedestrian "
                                          "a row of the batch)")
    p.add_argument("--out", default="runs/learned-crowd")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--worlds", type=int, default=32)
    p.add_argument("--iterations", type=int, default=300)
    p.add_argument("--threads", type=int, default=1)
    p.set_defaults(func=train_crowd_cmd)
    p = sub.add_parser("crowd-stats", help="goal arrivals and contacts of pedestrian models, no robot")
    p.add_argument("--models", default="orca,social_force,learned_crowd")
    p.add_argument("--episodes", type=int, default=10)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--humans", type=int, default=20)
    p.add_argument("--max-cycles", type=int, default=400)
    p.add_argument("--json", default=None)
    p.set_defaults(func=crowd_stats_cmd)
    p = sub.add_parser("plot", help="success trends of `tables` result files (ablation figure)")
    p.add_argument("results", nargs="+", help="JSON files written by `crowdbench tables --json`")
    p.add_argument("--out", default="trends.png")
    p.set_defaults(func=plot_cmd)
    p = sub.add_parser("curves", help="compare training runs (history.json files)")
    p.add_argument("histories", nargs="+")
    p.add_argument("--out", default="curves.png")
    p.add_argument("--evals", action="store_true",
                   help="plot quick-eval success against env steps and minutes (default: training success, reward)")
    p.add_argument("--table", type=float, default=None, metavar="BAR",
                   help="also print a markdown table: when each run's quick evaluation first reached BAR (e.g. 0.95); "
                        "with --evals the figure's bar line is drawn there too (default 0.95)")
    p.set_defaults(func=curves_cmd)
    p = sub.add_parser("panels", help="trajectory panels of one episode per layout (the paper's Fig. 4)")
    p.add_argument("policy_pos", nargs="?", default=None, metavar="POLICY")
    p.add_argument("--policy", default=None)
    p.add_argument("--checkpoint", default=None)
    p.add_argument("--humans", type=int, default=20)
    p.add_argument("--responsiveness", type=float, default=0.5)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default="trajectories.png")
    p.set_defaults(func=panels_cmd)
    p = sub.add_parser("bench", help="measure throughput (simulator, ORCA, training, inference)")
    p.add_argument("--quick", action="store_true", help="fewer steps and repeats")
    p.add_argument("--json", default=None, help="also write the figures to this JSON file")
    p.add_argument("--out", default="benchmarks", help="folder for RESULTS.md and throughput.png")
    p.set_defaults(func=bench_cmd)
    args = parser.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)  # the command as given (train --seeds repeats it)
    try:
        return args.func(args)
    except ValueError as e:  # bad input: one clear line
        print(f"crowdbench: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
