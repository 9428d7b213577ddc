"""The ``vidcap`` command line.

Each sub-command lives in its own module under :mod:`vidcap.commands` and exposes

* ``NAME``: the sub-command's name,
* ``HELP``: a one-line description,
* ``add_arguments(parser)``: fill an :class:`argparse.ArgumentParser`,
* ``run(args) -> int``: do the work and return the exit code,

and optionally ``OUTPUT_FILES`` / ``INPUT_FILES`` / ``OUTPUT_DIRS``, the names of its
file arguments, and ``implicit_inputs(args)``: each output is checked before the work
starts (not a folder, writable, not an input, not another output; see
:mod:`vidcap.outputguard`).

Modules are discovered at start-up, so adding a command never touches this file.
User errors (:class:`vidcap.errors.VidcapError`) print one line
``vidcap: error: <file>: <problem>`` and exit 2; ``--debug`` shows the traceback.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
import traceback

from vidcap import __version__
from vidcap.errors import VidcapError

EXIT_USER_ERROR = 2
EXIT_INTERNAL_ERROR = 1  # a bug in vidcap (bad input is EXIT_USER_ERROR)


def _command_modules():
    import vidcap.commands as pkg

    modules = []
    for info in sorted(pkgutil.iter_modules(pkg.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"vidcap.commands.{info.name}")
        if getattr(module, "NAME", None) and not getattr(module, "HIDDEN", False):
            modules.append(module)
    return sorted(modules, key=lambda m: getattr(m, "ORDER", 100))


def _check_outputs(args) -> None:
    """Fail before any work when an output cannot be written, is one of the inputs
    (explicit or implicit) or is another output (:mod:`vidcap.outputguard`)."""
    from vidcap.outputguard import guard_command

    guard_command(args._module, args)


def build_parser() -> argparse.ArgumentParser:
    """Return the top-level parser with every available sub-command."""
    parser = argparse.ArgumentParser(
        prog="vidcap",
        description="Single-camera video to 3D motion (BVH); joint centres from marker C3D.",
    )
    parser.add_argument("--version", action="version", version=f"vidcap {__version__}")
    parser.add_argument(
        "--debug", action="store_true", help="show full tracebacks instead of one-line errors"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in _command_modules():
        p = sub.add_parser(module.NAME, help=module.HELP, description=module.HELP)
        module.add_arguments(p)
        p.set_defaults(_run=module.run, _module=module)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the ``vidcap`` command; return the process exit code."""
    from vidcap import interrupt

    as_command = argv is None  # the process is ours: signals, and how it ends
    if as_command:
        interrupt.install()
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "_run", None):
        parser.print_help()
        return EXIT_USER_ERROR
    try:
        _check_outputs(args)
        from vidcap.video.hugepages import small_pages

        with small_pages():  # (the video stages' large temporaries: vidcap.video.hugepages)
            return int(args._run(args) or 0)
    except VidcapError as exc:
        if args.debug:
            traceback.print_exc()
        print(f"vidcap: error: {exc}", file=sys.stderr)
        return EXIT_USER_ERROR
    except MemoryError:
        print("vidcap: error: not enough memory for this input (try a shorter or smaller "
              "video, or --jobs 1)", file=sys.stderr)
        return EXIT_USER_ERROR
    except Exception as exc:  # noqa: BLE001 - a bug of ours: one line, not a traceback
        if as_command and interrupt.received():
            # (the interrupt itself, come back as another exception from a compiled
            # function it landed in: numba's dispatcher raises SystemError then)
            interrupt.stop_now()
        if args.debug:
            raise
        print(f"vidcap: internal error: {type(exc).__name__}: {exc} (a bug in vidcap, not in "
              "your input: rerun with --debug for the traceback and report it)",
              file=sys.stderr)
        return EXIT_INTERNAL_ERROR
    except KeyboardInterrupt:  # SIGINT, or SIGTERM (interrupt.install)
        if as_command:
            interrupt.stop_now()  # says so; the workers stopped, no waiting on them
        print("vidcap: interrupted", file=sys.stderr)
        return interrupt.EXIT_INTERRUPTED
