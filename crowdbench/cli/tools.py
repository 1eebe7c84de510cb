"""The other commands: ``predictor``, ``export``, ``crowd-validate``, ``crowd-stats``, ``plot``, ``curves`` and
``bench``."""

from __future__ import annotations

import argparse
import json
import os

from crowdbench.io import write_text
from crowdbench.policies import REFERENCE_METHOD, method_of, methods


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
        m = pt.train(data, out, tcfg, crowd=pt.recorded_crowd(args.data))
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


def plot_cmd(args: argparse.Namespace) -> int:
    """Plot success trends of several `crowdbench tables` result files."""
    from crowdbench.leaderboard.figures import plot_trends

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


def bench_cmd(args: argparse.Namespace) -> int:
    """Measure and print the throughput figures; write benchmarks/RESULTS.md and the throughput PNG."""
    from crowdbench.cli.bench import main as bench_main

    bench_main(quick=args.quick, json_path=args.json, out_dir=args.out)
    return 0


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """The sub-commands of this module."""
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
    p = sub.add_parser("crowd-validate", help="ADE/FDE of pedestrian models against the recorded ETH/UCY people")
    p.add_argument("--models", default="const_vel,orca,social_force,responsive_orca",
                   help="comma-separated: const_vel and any pedestrian model (default: %(default)s)")
    p.add_argument("--scenes", default=None, help="comma-separated subset of eth,hotel,univ,zara1,zara2 (default all)")
    p.add_argument("--json", default=None, help="write {scene: {model: {ade, fde, samples}}} to this file")
    p.set_defaults(func=crowd_validate_cmd)
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
    p = sub.add_parser("bench", help="measure throughput (simulator, ORCA, training, inference)")
    p.add_argument("--quick", action="store_true", help="fewer steps and repeats")
    p.add_argument("--json", default=None, help="also write the figures to this JSON file")
    p.add_argument("--out", default="benchmarks", help="folder for RESULTS.md and throughput.png")
    p.set_defaults(func=bench_cmd)
