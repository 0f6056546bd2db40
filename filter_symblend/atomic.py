"""Files written whole or not at all: written under a temporary name beside the target, renamed over it
at the end, so a failure or Ctrl-C never leaves a partial file nor touches the old one."""

from __future__ import annotations

import contextlib
import os
import pathlib
from collections.abc import Iterator

_PARTIAL: set[pathlib.Path] = set()  # this process's temporary files not yet renamed over their targets


@contextlib.contextmanager
def replaced_when_done(path: str | os.PathLike) -> Iterator[pathlib.Path]:
    """A hidden temporary path beside ``path``, with its suffix (so a writer that goes by the suffix writes
    the same format); it replaces ``path`` when the block ends without error and is removed in any case."""
    path = pathlib.Path(path)
    temporary = path.with_name(f".{path.stem}.symblend-partial{path.suffix}")
    _PARTIAL.add(temporary)
    try:
        yield temporary
        os.replace(temporary, path)
    except OSError as error:
        if error.filename is None:  # a full disk says so on write or close, naming no file: name the one written
            raise OSError(error.errno, error.strerror, str(path)) from error
        raise
    finally:
        temporary.unlink(missing_ok=True)
        _PARTIAL.discard(temporary)


def remove_partial_files() -> None:
    """Remove the temporary files of this process's writes in progress: for a process that must stop at once
    (a batch worker on SIGTERM) without unwinding, which an exception raised by a signal handler cannot
    promise (Python ignores one raised while it runs a finalizer)."""
    for temporary in list(_PARTIAL):
        temporary.unlink(missing_ok=True)


@contextlib.contextmanager
def all_or_none(paths: list) -> Iterator[list]:
    """Temporary paths for ``paths`` (None stays None): when the block ends without error all of them
    replace their paths, else none does (a run's outputs are one result: no mesh without its report)."""
    with contextlib.ExitStack() as stack:
        yield [None if path is None else stack.enter_context(replaced_when_done(path)) for path in paths]


def write_text(path: str | os.PathLike, text: str) -> None:
    """``text`` as the whole of ``path`` (UTF-8), or nothing written."""
    with replaced_when_done(path) as temporary:
        temporary.write_text(text, encoding="utf-8")
