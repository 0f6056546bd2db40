"""The ``symblend`` command's start-up: a Ctrl-C while pymeshlab and the commands load exits 130, one line.

Imported first by the commands package; it acts only when this process is the ``symblend`` console script, and
:func:`filter_symblend.commands.main.main` restores Python's own handler once start-up is over.
"""

from __future__ import annotations

import os
import signal
import sys


def _interrupted(signum, frame) -> None:
    sys.stderr.write("symblend: interrupted; no output written\n")
    os._exit(130)


def quiet_interrupt_while_loading() -> None:
    """Exit 130 without a traceback on Ctrl-C, when this process is the ``symblend`` command."""
    if os.path.basename(sys.argv[0]) in ("symblend", "symblend.exe") \
            and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _interrupted)
