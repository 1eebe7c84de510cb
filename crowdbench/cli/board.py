"""``crowdbench leaderboard``: ``run`` a suite, ``verify`` stored cells, ``list`` the entries and suites, set the board
beside the ``paper``."""

from __future__ import annotations

import argparse
import os

from crowdbench import checkpoints
from crowdbench.policies import POLICIES


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


def _default_out(args: argparse.Namespace, suite: str) -> str:
    """``--out``, else ``leaderboards`` for the paper suite as shipped, else ``runs/leaderboard-SUITE``."""
    return args.out or ("leaderboards" if args.suite == "paper" and args.episodes is None
                        else os.path.join("runs", f"leaderboard-{suite}"))


def leaderboard_run_cmd(args: argparse.Namespace) -> int:
    """A suite for every chosen method → ``OUT/<method>.json|md``, ``OUT/cells/`` and ``OUT/LEADERBOARD.md``."""
    from crowdbench import leaderboard

    suite = leaderboard.load_suite(args.suite, episodes=args.episodes)
    entries = _methods(args.methods, args.add)
    out = _default_out(args, suite.name)
    leaderboard.run_suite(suite, entries, out, workers=args.workers, backend=args.backend,
                          ray_address=args.ray_address, force=args.force, progress=leaderboard.print_progress)
    with open(os.path.join(out, "LEADERBOARD.md")) as f:
        print(f.read())
    return 0


def leaderboard_verify_cmd(args: argparse.Namespace) -> int:
    """Stored cells re-evaluated and compared bit for bit (:mod:`crowdbench.leaderboard.verify`); exit status 1 unless
    every one is identical."""
    from crowdbench import leaderboard
    from crowdbench.leaderboard.verify import markdown

    suite = leaderboard.load_suite(args.suite, episodes=args.episodes)
    cells = [c.strip() for c in args.cells.split(",") if c.strip()] if args.cells else None
    verdicts = leaderboard.verify_cells(suite, _methods(args.methods, []), _default_out(args, suite.name), cells,
                                        workers=args.workers, backend=args.backend, ray_address=args.ray_address)
    print(markdown(verdicts))
    bad = [v for v in verdicts if v.status != "identical"]
    print(f"{len(verdicts) - len(bad)} of {len(verdicts)} stored cells identical"
          + (f"; not identical: {', '.join(f'{v.label} {v.cell} ({v.status})' for v in bad)}" if bad else ""))
    return 1 if bad else 0


def leaderboard_list_cmd(args: argparse.Namespace) -> int:
    """The shipped leaderboard entries, every registered policy with its shipped checkpoints, and the suites."""
    from crowdbench import leaderboard

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
    for name in leaderboard.suite_names():
        s = leaderboard.load_suite(name)
        print(f"  {name:<10} {len(s.grid()):>2} cells × {s.episodes} episodes, seed {s.seed} — {s.description}")
    return 0


def paper_cmd(args: argparse.Namespace) -> int:
    """Every stored board cell beside the paper's number (:mod:`crowdbench.leaderboard.paper`); reads cells, runs
    nothing."""
    from crowdbench.leaderboard import paper

    print(paper.report(args.out, args.md))
    return 0


def compare_cmd(args: argparse.Namespace) -> int:
    """Two methods over their training seeds, setting by setting (:mod:`crowdbench.leaderboard.compare`); reads
    cells, runs nothing."""
    from crowdbench.leaderboard import compare

    print(compare.markdown(compare.compare(args.out, args.a, args.b)))
    return 0


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """The sub-commands of this module."""
    p = sub.add_parser("leaderboard", help="score methods on a suite (run), re-check stored cells (verify), or list "
                                           "methods and suites (list)")
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
    q = lsub.add_parser("verify", help="re-evaluate stored cells and compare them with the stored ones, bit for bit")
    q.add_argument("--suite", default="paper", help="the suite the cells belong to (default paper)")
    q.add_argument("--episodes", type=int, default=None, help="the episodes per cell the cells were run with, if "
                                                              "run overrode the suite's")
    q.add_argument("--methods", default=None, help="comma-separated entries, as for run (default: every shipped entry)")
    q.add_argument("--cells", default=None, metavar="KEY,...",
                   help="cell keys such as I-medium,II-n-20 (the file stems under OUT/cells/ENTRY/; default: all)")
    q.add_argument("--workers", type=int, default=1, help="cells evaluated in parallel (processes or Ray tasks)")
    q.add_argument("--backend", default="local", help="local (this machine) or ray (crowdbench[ray])")
    q.add_argument("--ray-address", default=None, help="an existing Ray cluster (default: a local Ray instance)")
    q.add_argument("--out", default=None,
                   help="results folder (default, as for run: leaderboards for the paper suite, else "
                        "runs/leaderboard-SUITE)")
    q.set_defaults(func=leaderboard_verify_cmd)
    q = lsub.add_parser("paper", help="every stored cell beside the paper's Tables I–III (reads cells only)")
    q.add_argument("--out", default="leaderboards", help="the leaderboard folder (default leaderboards)")
    q.add_argument("--md", default=None, help="markdown file to write (default OUT/PAPER.md)")
    q.set_defaults(func=paper_cmd)
    q = lsub.add_parser("compare", help="two methods over their training seeds, setting by setting: means, "
                                         "differences, seed pairs with intervals apart (reads cells only)")
    q.add_argument("a", help="a method: LABEL (its stored entries LABEL and LABEL-seedK), LABEL, (that entry alone) or "
                                  "LABEL,LABEL,…")
    q.add_argument("b", help="the method to compare it with, alike")
    q.add_argument("--out", default="leaderboards", help="the leaderboard folder (default leaderboards)")
    q.set_defaults(func=compare_cmd)
    q = lsub.add_parser("list", help="shipped entries, registered policies with checkpoints, suites")
    q.set_defaults(func=leaderboard_list_cmd)
