"""``crowdbench train`` (a PPO or a value method; its options are the training configs' fields) and
``crowdbench train-crowd``."""

from __future__ import annotations

import argparse
import os

from crowdbench import checkpoints
from crowdbench.policies import trained_by

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


def train_crowd_cmd(args: argparse.Namespace) -> int:
    """Train the shared pedestrian policy (:mod:`crowdbench.training.crowd`) → ``OUT/learned_crowd.pt``."""
    from crowdbench.training.crowd import CrowdTrainConfig, train

    cfg = CrowdTrainConfig(seed=args.seed, worlds=args.worlds, iterations=args.iterations, threads=args.threads)
    train(cfg, args.out)
    print(f"wrote {os.path.join(args.out, 'learned_crowd.pt')} and history.json")
    return 0


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """The sub-commands of this module."""
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
    p = sub.add_parser("train-crowd", help="train the learned_crowd pedestrian policy (rsl-rl PPO, every pedestrian "
                                          "a row of the batch)")
    p.add_argument("--out", default="runs/learned-crowd")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--worlds", type=int, default=32)
    p.add_argument("--iterations", type=int, default=300)
    p.add_argument("--threads", type=int, default=1)
    p.set_defaults(func=train_crowd_cmd)
