"""One ``symblend batch`` at a time per output folder: a lock file that says who holds it.

Two runs on one folder would each recompute every specimen and overwrite each other's summary. The lock
is a file created exclusively in the folder, holding the process id, the host and the start time; it is
removed when the run ends, however it ends. A lock left by a run that was killed (SIGKILL, a crash) is
stale when its process no longer exists on this host, and is taken over.
"""

from __future__ import annotations

import contextlib
import json
import os
import pathlib
import socket
import time
from collections.abc import Iterator

from ...errors import SymblendError

LOCK_NAME = ".symblend-batch.lock"
POLL_SECONDS = 1.0


def _holder(lock: pathlib.Path) -> dict | None:
    """What the lock file says (pid, host, since), or None if it is gone or unreadable (being written)."""
    try:
        return json.loads(lock.read_text())
    except (OSError, ValueError):
        return None


def _stale(holder: dict) -> bool:
    """Whether the run that holds the lock is gone: same host, no such process."""
    if holder.get("host") != socket.gethostname():
        return False  # another machine's run (a shared folder): only it can say
    try:
        os.kill(int(holder["pid"]), 0)
    except ProcessLookupError:
        return True
    except (PermissionError, KeyError, ValueError, TypeError):
        return False
    return False


def _try_lock(lock: pathlib.Path) -> bool:
    try:
        handle = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
    except FileExistsError:
        return False
    with os.fdopen(handle, "w") as file:
        json.dump({"pid": os.getpid(), "host": socket.gethostname(), "since": time.strftime("%Y-%m-%d %H:%M:%S")}, file)
    return True


@contextlib.contextmanager
def folder_lock(folder: pathlib.Path, wait: bool = False) -> Iterator[None]:
    """Hold ``folder``'s batch lock for the block; if another live run holds it, SymblendError naming that run
    (or, with ``wait``, wait for it to end)."""
    lock = folder / LOCK_NAME
    while not _try_lock(lock):
        holder = _holder(lock)
        if holder is not None and _stale(holder):
            lock.unlink(missing_ok=True)  # its run was killed: take the folder over
            continue
        if not wait:
            said = "" if holder is None else (f" (process {holder.get('pid')} on {holder.get('host')}, since "
                                              f"{holder.get('since')})")
            raise SymblendError(f"{folder}: another symblend batch{said} is writing this folder; wait for it "
                                f"(--wait), or give another folder. If no such run exists, delete {lock}.")
        time.sleep(POLL_SECONDS)
    try:
        yield
    finally:
        lock.unlink(missing_ok=True)
