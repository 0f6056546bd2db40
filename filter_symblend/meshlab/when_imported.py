"""Bind the filter onto ``pymeshlab.MeshSet`` as soon as pymeshlab is imported, without importing it.

``import filter_symblend`` binds the filter, yet the array API (``filter_symblend.core`` and the floors
above it up to ``pipeline``) must import without pymeshlab. So the package root calls
:func:`bind_when_pymeshlab_imported`: if pymeshlab is already loaded, the filter is bound now; otherwise a
one-shot finder on ``sys.meta_path`` lets Python load pymeshlab as usual and binds right after (the
post-import hook of PEP 369, which wrapt's ``when_imported`` also implements). This module imports nothing
of pymeshlab itself.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import sys

_MODULE = "pymeshlab"


def _bind() -> None:
    from .meshset_filter import bind_to_meshset  # imports pymeshlab, loaded by now
    bind_to_meshset()


class _LoadThenBind(importlib.abc.Loader):
    """pymeshlab's own loader, followed by the binding."""

    def __init__(self, loader):
        self._loader = loader

    def create_module(self, spec):
        return self._loader.create_module(spec)

    def exec_module(self, module) -> None:
        self._loader.exec_module(module)
        module.__loader__ = module.__spec__.loader = self._loader  # loaded: leave no trace of the wrapper
        _bind()

    def __getattr__(self, name):  # resource readers, is_package, get_code...: pymeshlab's loader answers
        return getattr(self._loader, name)


class _BindAfterImport(importlib.abc.MetaPathFinder):
    """Finds nothing itself: asks the other finders for pymeshlab and wraps the loader they give."""

    def find_spec(self, name, path=None, target=None):
        if name != _MODULE:
            return None
        sys.meta_path.remove(self)  # one shot, and no recursion into itself below
        spec = importlib.util.find_spec(name)
        if spec is None or spec.loader is None:
            return None  # not installed: nothing to bind, and Python reports the import as usual
        spec.loader = _LoadThenBind(spec.loader)
        return spec


def bind_when_pymeshlab_imported() -> None:
    """Bind ``MeshSet.generate_symmetrized_mesh`` now if pymeshlab is loaded, else right after it loads."""
    if _MODULE in sys.modules:
        if sys.modules[_MODULE] is not None:  # None: someone blocked the import on purpose
            _bind()
    elif not any(isinstance(finder, _BindAfterImport) for finder in sys.meta_path):
        sys.meta_path.insert(0, _BindAfterImport())
