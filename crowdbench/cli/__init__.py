"""``crowdbench`` command line: ``demo`` (one rendered episode → GIF), ``evaluate`` (batched metrics), ``train``,
``leaderboard`` and the tools.

The applications live in this package, one module per family of commands (each adds its sub-commands with
``add_parsers``): :mod:`~crowdbench.cli.episodes`, :mod:`~crowdbench.cli.train`, :mod:`~crowdbench.cli.board`,
:mod:`~crowdbench.cli.tools`; with the throughput benchmark (:mod:`~crowdbench.cli.bench`, also importable as
``crowdbench.bench``) and the trajectory panels (:mod:`~crowdbench.cli.panels`).
"""

from __future__ import annotations

import argparse
import sys

from crowdbench.cli import board, episodes, tools, train


def main(argv: list[str] | None = None) -> int:
    """Run the command line ``argv`` (default: ``sys.argv[1:]``); returns the exit code (2 on bad input)."""
    parser = argparse.ArgumentParser(prog="crowdbench", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    for family in (episodes, train, board, tools):
        family.add_parsers(sub)
    args = parser.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)  # the command as given (train --seeds repeats it)
    try:
        return args.func(args)
    except ValueError as e:  # bad input: one clear line
        print(f"crowdbench: error: {e}", file=sys.stderr)
        return 2
