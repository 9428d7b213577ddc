"""Lazy access to the optional ``vidcap.ui`` package for the interactive commands."""

from __future__ import annotations

import importlib

from vidcap.errors import UsageError

#: What to install when the interactive extras are missing.
INSTALL_HINT = "pip install 'vidcap[ui]'"


def require(module: str, *, needs: tuple[str, ...] = ()):
    """Import ``module`` (e.g. ``'vidcap.ui.view'``); a missing extra becomes one clear error.

    Parameters
    ----------
    module : str
        Module of the ``vidcap.ui`` package to import.
    needs : tuple of str
        Third-party packages the module needs (checked first, so the error names them).

    Raises
    ------
    UsageError
        If ``vidcap.ui`` or one of ``needs`` cannot be imported.
    """
    for name in (*needs, module):
        try:
            importlib.import_module(name)
        except ImportError as exc:
            missing = getattr(exc, "name", None) or name
            raise UsageError(
                f"this command needs the interactive extras ({missing} is not installed):"
                f" {INSTALL_HINT}") from None
    return importlib.import_module(module)
