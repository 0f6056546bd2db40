"""``symblend``: the parser of every subcommand, and :func:`main`, the console script's entry point."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import warnings

from ..errors import SymblendError, SymblendWarning
from . import batch, landmark_files, mirror_pairs, mlx, report, symmetrize
from .shared.console import Parser, one_line, show_warning

DESCRIPTION = ("The symblend command: symmetrize a mesh from a landmark file or a whole study, run filter scripts, "
               "compare before and after, check and convert landmarks, write automatic pairs to check.")


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``symblend`` and its subcommands; each sets ``handler``, the function that runs it."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        installed = version("filter-symblend")
    except PackageNotFoundError:
        installed = "unknown (not installed)"
    parser = Parser(prog="symblend", description=DESCRIPTION)
    parser.add_argument("--version", action="version", version=f"symblend (filter-symblend) {installed}")
    commands = parser.add_subparsers(dest="command", required=True)
    for command in (symmetrize, mirror_pairs, batch, mlx, report, landmark_files):
        command.register(commands)
    return parser


class Terminated(KeyboardInterrupt):
    """SIGTERM (a batch scheduler, a cluster's time limit), raised where Python next runs: the run stops as on
    Ctrl-C, every partial output removed on the way out."""


def _terminate(signum, frame) -> None:
    raise Terminated()


def main(argv=None) -> int:
    """Exit status: 0 done, 1 bad input (one line on stderr, nothing written), 2 usage, 130 interrupted,
    143 terminated (SIGTERM)."""
    signal.signal(signal.SIGINT, signal.default_int_handler)  # start-up is over: Ctrl-C is KeyboardInterrupt
    for stream in (sys.stdout, sys.stderr):  # a file name that is not UTF-8 is printed escaped, not a traceback
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    in_main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _terminate) if in_main_thread else None
    left = "no output written"  # what a stopped command leaves: its outputs are one transaction
    try:
        args = build_parser().parse_args(argv)
        left = getattr(args, "stopped_leaves", lambda _: left)(args)
        with warnings.catch_warnings():
            # numpy/scipy warnings are expected where results are checked (the core raises on any
            # non-finite output); ours name a cause and a fix.
            warnings.simplefilter("ignore")
            warnings.simplefilter("always", SymblendWarning)
            warnings.showwarning = show_warning
            return args.handler(args)
    except SymblendError as error:
        print(f"symblend: error: {one_line(error)}", file=sys.stderr)
        return 1
    except OSError as error:
        print(f"symblend: error: {error.filename}: {error.strerror}", file=sys.stderr)
        return 1
    except Terminated:
        print(f"symblend: terminated; {left}", file=sys.stderr)
        return 143
    except KeyboardInterrupt:
        print(f"symblend: interrupted; {left}", file=sys.stderr)
        return 130
    finally:
        if in_main_thread:
            signal.signal(signal.SIGTERM, previous)  # main() called from Python leaves the caller's handler

