"""Sub-commands of ``vidcap``; each module is discovered by :mod:`vidcap.cli`."""
