"""Files written whole or not at all: written under a temporary name beside the target, renamed over it
at the end, so a failure or Ctrl-C never leaves a partial file nor touches the old one."""

from __future__ import annotations

import contextlib
import os
import pathlib
from collections.abc import Iterator


@contextlib.contextmanager
def replaced_when_done(path: str | os.PathLike) -> Iterator[pathlib.Path]:
    """A hidden temporary path beside ``path``, with its suffix (so a writer that goes by the suffix writes
    the same format); it replaces ``path`` when the block ends without error and is removed in any case."""
    path = pathlib.Path(path)
    temporary = path.with_name(f".{path.stem}.symblend-partial{path.suffix}")
    try:
        yield temporary
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)


def write_text(path: str | os.PathLike, text: str) -> None:
    """``text`` as the whole of ``path`` (UTF-8), or nothing written."""
    with replaced_when_done(path) as temporary:
        temporary.write_text(text, encoding="utf-8")
