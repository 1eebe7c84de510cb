"""``crowdbench train`` (a PPO or a value method; its options are the training configs' fields) and
``crowdbench train-crowd``."""

from __future__ import annotations

import argparse
import dataclasses
import os

from crowdbench import checkpoints
from crowdbench.cli import options
from crowdbench.policies import trained_by

CONFIG_EXCLUDED = {
    "method": "the positional METHOD",
    "model": "the architecture: --variant and --model FIELD=VALUE (PPO methods)",
    "init": "set by --init CHECKPOINT (the provenance of the weights a run starts from), not by hand",
    "extra": "free-form notes stored with a run, not a setting",
}
"""Fields of the training configs with no option of their own, and why (``tests/test_cli_options.py``)."""
CONFIG_FLAGS = {"num_envs": "envs"}
"""Options named otherwise than their field."""


def train_options() -> list[options.FieldOption]:
    """The ``crowdbench train`` options of the training configs' fields: PPO's
    :class:`~crowdbench.training.config.TrainConfig` and the value methods'
    :class:`~crowdbench.training.value.ValueTrainConfig` (:mod:`crowdbench.cli.options`)."""
    from crowdbench.training.config import TrainConfig
    from crowdbench.training.value import ValueTrainConfig

    return options.config_options((TrainConfig, ValueTrainConfig), exclude=tuple(CONFIG_EXCLUDED), flags=CONFIG_FLAGS,
                                  labels={TrainConfig: "PPO", ValueTrainConfig: "value methods"})


def _foreign(args: argparse.Namespace, cls: type, extra: tuple[str, ...] = ()) -> list[str]:
    """The options given that set no field of ``cls`` (plus the non-field options ``extra`` that were given)."""
    mine = {f.name for f in dataclasses.fields(cls)}
    return [*(f"--{k}" for k in extra if getattr(args, k) is not None),
            *(o.shown() for o in train_options() if o.field not in mine and getattr(args, o.field) is not None)]


def _resumed(args: argparse.Namespace, resumable: tuple[str, ...]) -> dict[str, object]:
    """The given fields a resumed run may change; one clear error for the others (``--seed`` is checked against
    the run's own once it is read)."""
    given = options.given(args, train_options())
    fixed = [o.shown(given[o.field]) for o in train_options()
             if o.field in given and o.field not in (*resumable, "seed")]
    if fixed:
        raise ValueError(f"{', '.join(fixed)}: a resumed run keeps its configuration; drop them with --resume "
                         f"(only {', '.join('--' + k.replace('_', '-') for k in resumable)} may change)")
    return {k: v for k, v in given.items() if k in resumable}


def _check_seed(args: argparse.Namespace, seed: int) -> None:
    if args.seed is not None and args.seed != seed:
        raise ValueError(f"--seed {args.seed}: the resumed run's seed is {seed}; valid choices: {seed} or no --seed")


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
    misplaced = _foreign(args, TrainConfig)
    if misplaced:
        raise ValueError(f"{', '.join(misplaced)}: options of the value-based methods ({', '.join(value_methods)}), "
                         f"not of {args.algo}")
    method = PPO_METHODS.get(args.algo)()
    check_start(args.resume, args.init)  # before the resumed checkpoint is read
    if args.resume:  # a resumed run keeps its configuration; only its budget and speed settings may change
        if args.variant is not None or args.model:
            raise ValueError("--variant/--model: a resumed run keeps its architecture; drop them with --resume")
        speed = _resumed(args, RESUMABLE)
        path = checkpoints.run_checkpoint(args.resume)
        cfg = resume_config(path, **speed)
        _check_seed(args, cfg.seed)
        out = args.out or os.path.dirname(os.path.abspath(path))
    else:
        model = {**method.variant_model(args.variant), **method.model_overrides(args.model or [])}
        cfg = TrainConfig.for_method(args.algo, model=model, **options.given(args, train_options()))
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


def train_value_cmd(args: argparse.Namespace) -> int:
    """CADRL / SARL: imitation of the ORCA robot, then TD learning (:mod:`crowdbench.training.value`)."""
    from crowdbench.training.value import RESUMABLE, ValueTrainConfig, resume_config, train_value

    ppo_only = _foreign(args, ValueTrainConfig, extra=("variant", "model", "init"))
    if ppo_only:
        raise ValueError(f"{', '.join(ppo_only)}: options of the PPO methods, not of {args.algo}")
    if args.resume:
        speed = _resumed(args, RESUMABLE)
        path = checkpoints.run_checkpoint(args.resume)
        cfg = resume_config(path, **speed)
        if cfg.method != args.algo:
            raise ValueError(f"--resume: {path!r} is a {cfg.method} run, not {args.algo}")
        _check_seed(args, cfg.seed)
        out = args.out or os.path.dirname(os.path.abspath(path))
    else:
        cfg = ValueTrainConfig(method=args.algo, **options.given(args, train_options()))
        tier = "" if cfg.sensing == "positions" else f"-{cfg.sensing}"  # never the positions run's folder
        out = args.out or os.path.join("runs", f"{args.algo}{tier}-seed{cfg.seed}")
    print(f"training {cfg.method} seed={cfg.seed} sensing={cfg.sensing} → {out}")
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
    p = sub.add_parser("train", help="train a learned method: rsl-rl PPO or value learning (its `trainer`)",
                       description="Train a learned method; a resumed run (--resume) keeps its configuration but "
                                   "for its budget and speed settings.")
    p.add_argument("algo", metavar="METHOD",
                   help=f"a method crowdbench trains: {', '.join([*trained_by('ppo'), *trained_by('value')])}")
    p.add_argument("--variant", default=None, help="a named architecture of the method (its PPO binding's variants; "
                        "default: its default variant)")
    p.add_argument("--model", action="append", default=None, metavar="FIELD=VALUE",
                   help="architecture field over the variant's (repeatable), e.g. --model d_model=64 --model "
                        "gru_hidden=128; the fields are the method's architecture config")
    p.add_argument("--seeds", default=None, metavar="S,S,...",
                   help="train several seeds, each a run of its own under OUT/seedS, in parallel processes "
                        "(--backend local) or as Ray tasks (--backend ray); equal to training them one by one")
    p.add_argument("--backend", default="local", choices=("local", "ray"), help="with --seeds (default local)")
    p.add_argument("--seed-workers", type=int, default=None, help="with --seeds --backend local: processes "
                                                                  "(default one per seed, at most the cores)")
    p.add_argument("--ray-address", default=None, help="with --seeds --backend ray: an existing cluster")
    p.add_argument("--out", default=None,
                   help="run folder (default runs/VARIANT-seedS; a value method at another sensing tier: "
                        "runs/METHOD-TIER-seedS)")
    p.add_argument("--resume", default=None, help="run folder or checkpoint to continue exactly")
    p.add_argument("--init", default=None, metavar="CHECKPOINT",
                   help="start a new run from this run's network weights (same architecture; the noise fields "
                        "action_std/learn_std, schedule, optimiser and counters are the new run's): fine-tuning")
    group = p.add_argument_group("training configuration", "one option per field of the PPO methods' TrainConfig "
                                 "and the value methods' ValueTrainConfig; unset: the field's default (a PPO "
                                 "method's recipe may set its own)")
    options.add_options(group, train_options())
    p.set_defaults(func=train_cmd)
    p = sub.add_parser("train-crowd", help="train the learned_crowd pedestrian policy (rsl-rl PPO, every pedestrian "
                                          "a row of the batch)")
    p.add_argument("--out", default="runs/learned-crowd")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--worlds", type=int, default=32)
    p.add_argument("--iterations", type=int, default=300)
    p.add_argument("--threads", type=int, default=1)
    p.set_defaults(func=train_crowd_cmd)
