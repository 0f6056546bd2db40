"""What the ``symblend`` command shows on the console: one-line errors and warnings, a progress line,
and argparse's usage errors pointing to ``--help``. A leaf of the commands: it imports only the errors."""

from __future__ import annotations

import argparse
import sys

from ...errors import SymblendError


def one_line(error: Exception | Warning | str) -> str:
    """``error``'s text on one line."""
    return " ".join(str(error).split())


def terminal_progress(percent: float, message: str) -> None:
    """A one-line progress display on a terminal, rewritten in place."""
    bar = "#" * int(percent / 5)
    print(f"\r[{bar:<20}] {percent:3.0f}% {message:<40}", end="\n" if percent >= 100 else "",
          file=sys.stderr, flush=True)


def progress_display():
    """:func:`terminal_progress` when stderr is a terminal, else None (no progress)."""
    return terminal_progress if sys.stderr.isatty() else None


def show_warning(message, category, *rest) -> None:
    """``warnings.showwarning`` for the command: one line on stderr."""
    print(f"symblend: warning: {one_line(message)}", file=sys.stderr)


class Parser(argparse.ArgumentParser):
    """argparse with a one-line usage error (exit status 2) that points to ``--help``."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see: {self.prog} --help)\n")


class RaisingParser(Parser):
    """The same options, whose usage errors raise SymblendError (a batch row's options)."""

    def error(self, message: str):
        raise SymblendError(message)
