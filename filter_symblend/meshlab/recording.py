"""Which parts of a MeshSet's recorded filter script are calls of our filter.

pymeshlab records the native filters a MeshSet applies (``save_filter_script``)
but not Python methods bound onto it, and it records the native steps our
filter uses internally. Each call of our filter is remembered here as the
range of native steps it recorded and its parameters, so the script can be
saved with our node in place of those steps (see ``script_runner``).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import weakref
import xml.etree.ElementTree as ElementTree

import pymeshlab

_CALLS: "weakref.WeakKeyDictionary[pymeshlab.MeshSet, list]" = weakref.WeakKeyDictionary()


def recorded_native_script(ms: pymeshlab.MeshSet) -> ElementTree.Element:
    """The ``<FilterScript>`` element pymeshlab has recorded for ``ms`` so far."""
    handle, path = tempfile.mkstemp(suffix=".mlx")
    os.close(handle)
    try:
        ms.save_filter_script(path)
        return ElementTree.parse(path).getroot()
    finally:
        os.unlink(path)


@contextlib.contextmanager
def recorded_call(ms: pymeshlab.MeshSet, options: dict):
    """Remember that the native steps recorded inside the block are one call with ``options``."""
    start = len(recorded_native_script(ms))
    yield
    _CALLS.setdefault(ms, []).append((start, len(recorded_native_script(ms)), dict(options)))


def recorded_calls(ms: pymeshlab.MeshSet) -> list[tuple[int, int, dict]]:
    """(first native step, end, parameters) of each call of our filter on ``ms``, in order."""
    return list(_CALLS.get(ms, []))
