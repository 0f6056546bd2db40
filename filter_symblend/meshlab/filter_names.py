"""MeshLab filter names across MeshLab's versions, and the pymeshlab filter each one runs.

A script names a filter by its MeshLab name (the Filters menu's), as the
version that wrote it spelled it. The name is resolved in three steps:
MeshLab's history (``meshlab_filter_history.json``: filters renamed since
1.3.x, with their parameters translated, and filters removed, some with a replacement the
user may accept), then the
MeshLab names of today's filters (pymeshlab's rename table ``keys.txt`` of
MeshLab 2021.x names, and the names recorded from pymeshlab itself), then
pymeshlab's own rule against its filter list. Names compare as pymeshlab compares them (case,
spaces and punctuation aside).
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import json
import pathlib

import pymeshlab

HISTORY_FILE = pathlib.Path(__file__).with_name("meshlab_filter_history.json")

# pymeshlab's keyword list, quirk included ("def\tfrom" is one entry: neither gets a "_").
_PYTHON_KEYWORDS = {"False", "await", "else", "import", "pass", "None", "break", "except", "in", "raise",
                    "True", "class", "finally", "is", "return", "and", "continue", "for", "lambda", "try",
                    "as", "def\tfrom", "nonlocal", "while", "assert", "del", "global", "not", "with",
                    "async", "elif", "if", "or", "yield"}


def python_name(name: str) -> str:
    """pymeshlab's rule turning a MeshLab name into a Python one (its ``computePythonName``)."""
    out = name.lower().replace(" ", "_").replace("/", "_").replace("-", "_")
    out = "".join(ch for ch in out if ch not in "().,'\":+")
    return out + "_" if out in _PYTHON_KEYWORDS else out


@dataclasses.dataclass(frozen=True)
class Rename:
    """An old MeshLab filter name and what it is now. ``parameters``: old ``<Param>`` name ->
    {"name": now, "type": the .mlx type now, "values": old value -> now}; ``added``: parameter
    name -> {"type", "value"} the filter needs now to do what the old one did."""

    old: str
    now: str
    seen_in: str
    parameters: dict
    added: dict


@dataclasses.dataclass(frozen=True)
class Replacement:
    """What runs instead of a removed filter when the user accepts it: ``now`` (None: the step is
    dropped), ``parameters`` and ``added`` as in :class:`Rename`, ``dropped``: old parameter name -> why
    it has no counterpart."""

    now: str | None
    parameters: dict
    added: dict
    dropped: dict


@dataclasses.dataclass(frozen=True)
class Removal:
    name: str
    dropped_in: str
    instead: str | None
    replacement: Replacement | None = None


@functools.lru_cache(maxsize=None)
def _history() -> tuple[dict[str, Rename], dict[str, Removal], dict[str, str]]:
    table = json.loads(HISTORY_FILE.read_text(encoding="utf-8"))
    renames = {python_name(r["old"]): Rename(r["old"], r["now"], r["seen_in"], r.get("parameters", {}),
                                             r.get("add", {})) for r in table["renamed"]}
    removals = {python_name(r["name"]): Removal(r["name"], r["dropped_in"], r["instead"], _replacement(r))
                for r in table["removed"]}
    return renames, removals, table.get("display_names", {})


def _replacement(removal: dict) -> Replacement | None:
    given = removal.get("replacement")
    if given is None:
        return None
    return Replacement(given["now"], given.get("parameters", {}), given.get("add", {}), given.get("dropped", {}))


def renamed(name: str) -> Rename | None:
    """What MeshLab's history says the filter ``name`` is now, or None if it was not renamed."""
    return _history()[0].get(python_name(name))


def removed(name: str) -> Removal | None:
    """The removal of the filter ``name`` from MeshLab, or None if it was not removed."""
    return _history()[1].get(python_name(name))


def meshlab_name(filter_name: str) -> str | None:
    """The MeshLab (menu) name of the pymeshlab filter ``filter_name``, where it is known."""
    return _history()[2].get(filter_name)


@functools.lru_cache(maxsize=None)
def _pymeshlab_renames() -> dict[str, str]:
    """pymeshlab's table of 2022 renames: Python form of the MeshLab name -> current name."""
    keys = pathlib.Path(pymeshlab.__file__).with_name("keys.txt")
    if not keys.is_file():
        return {}
    return dict(line.split() for line in keys.read_text().splitlines() if len(line.split()) == 2)


@functools.lru_cache(maxsize=None)
def _by_meshlab_name() -> dict[str, str]:
    """Python form of a MeshLab name -> pymeshlab filter: pymeshlab's 2022 table, then the names
    recorded from pymeshlab itself (which include filters added or renamed since)."""
    table = dict(_pymeshlab_renames())
    table.update({python_name(shown): f for f, shown in _history()[2].items()})
    return table


def pymeshlab_filter_name(meshlab_filter: str) -> str | None:
    """The pymeshlab filter a current MeshLab name runs, or None if there is none.

    A filter added to MeshLab after pymeshlab's 2022 rename table and absent
    from the recorded names (one that needs rasters, textures or a second mesh
    to run, see scripts/meshlab_display_names.py) is reported as unknown.
    """
    snake = python_name(meshlab_filter)
    name = _by_meshlab_name().get(snake, snake)
    return name if name in pymeshlab.filter_list() else None


def closest_filter(name: str, extra: dict[str, str]) -> tuple[str | None, str | None] | None:
    """(MeshLab name now, pymeshlab name) of the known filter closest to ``name``, or None; either
    may be None: a filter whose MeshLab name is not recorded, or one of ``extra`` (Python form ->
    MeshLab name: our own filter). Candidates: pymeshlab's filters by their MeshLab names of 2021
    and now, the old names of the history (suggested by their name now), and ``extra``."""
    renames, _, display = _history()
    candidates = {key: (display.get(filter_name), filter_name) for key, filter_name in _pymeshlab_renames().items()}
    candidates.update({python_name(shown): (shown, filter_name) for filter_name, shown in display.items()})
    candidates.update({key: (meshlab_name(pymeshlab_filter_name(r.now)) or r.now, pymeshlab_filter_name(r.now))
                       for key, r in renames.items()})
    candidates.update({key: (shown, None) for key, shown in extra.items()})
    close = difflib.get_close_matches(python_name(name), list(candidates), n=1, cutoff=0.6)
    return candidates[close[0]] if close else None
