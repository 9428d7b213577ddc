"""The one output guard every command goes through before any work.

Each output path (``-o``, ``--save``, ``--centres``, ``--report``, ``--png``,
``--draft-markerset``, ``.glb`` outputs, a batch's files) is compared, after resolving
symbolic links (and by inode, for hard links), with every input the command will read,
including the implicit ones (``VIDEO_STEM.vidcap.json`` annotations, a marker-set file,
``--also`` trials), and with every other output. A clash is refused with one line
naming the file and both roles, so no command can overwrite what it reads or write two
results to one file.

A command module declares its file arguments by name (``OUTPUT_FILES``,
``INPUT_FILES``, ``OUTPUT_DIRS``; list-valued arguments such as ``--also`` are
flattened) and, for the implicit ones, ``implicit_inputs(args)`` and
``implicit_outputs(args)`` functions.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

from vidcap.errors import UsageError
from vidcap.fileio import check_output_file


def _flat(value) -> list:
    if value is None:
        return []
    if isinstance(value, (list, tuple)):
        return [v for item in value for v in _flat(item)]
    return [value]


def _flag(name: str) -> str:
    if name == "gltf_bin":
        return "the .bin beside the -o .gltf"
    return "-o" if name in ("output", "outdir") else "--" + name.replace("_", "-")


def _same(a: Path, b: Path) -> bool:
    """Whether two paths name one file: equal once links are resolved, or one inode."""
    if a.resolve() == b.resolve():
        return True
    try:
        return a.exists() and b.exists() and a.samefile(b)
    except OSError:
        return False


def check_outputs(outputs: Mapping[str, object], inputs: Mapping[str, object], *,
                  output_dirs: Mapping[str, object] | None = None) -> None:
    """Refuse, before any work, outputs that clash with an input or with each other.

    Parameters
    ----------
    outputs : mapping of role -> path or list of paths (None entries skipped)
        Files the command will write, by their option (``"output"``, ``"save"``...).
    inputs : mapping of role -> path or list of paths
        Files it will read; only those that exist can be destroyed, so only those count.
    output_dirs : mapping of role -> path
        Folders it will write files into (``--png DIR``): refused when they are an input
        file, or hold an input of the kind they receive (a ``.png`` in a ``--png`` folder).

    Raises
    ------
    vidcap.errors.UsageError
        Naming the output and what it clashes with.
    """
    ins = [(role, Path(p)) for role, v in inputs.items() for p in _flat(v)]
    ins = [(role, p) for role, p in ins if p.is_file()]
    outs = [(role, Path(p)) for role, v in outputs.items() for p in _flat(v)]
    for role, out in outs:
        check_output_file(out)
        for in_role, src in ins:
            if _same(out, src):
                raise UsageError(f"{_flag(role)} is also an input of this command"
                                 f" ({_input_role(in_role)}): writing it would destroy it", out)
    for i, (role, out) in enumerate(outs):
        for other_role, other in outs[:i]:
            if _same(out, other):
                both = (f"given as both {_flag(other_role)} and {_flag(role)}"
                        if role != other_role else f"two of the {_flag(role)} files")
                raise UsageError(f"{both}: one would overwrite the other", out)
    dirs = [(r, Path(p)) for r, v in (output_dirs or {}).items() for p in _flat(v)]
    for role, folder in dirs:
        if folder.exists() and not folder.is_dir():
            raise UsageError(f"{_flag(role)} must be a folder, and this is a file", folder)
        for in_role, src in ins:
            if _same(src.parent, folder) and src.suffix.lower() == ".png":
                raise UsageError(f"{_flag(role)} holds an input ({_input_role(in_role)}"
                                 f" {src.name}) its PNG frames could overwrite", folder)


def _input_role(role: str) -> str:
    return {"trial": "the trial", "video": "the video", "also": "an --also trial",
            "implicit_annotations": "the annotations read by default"}.get(
        role, _flag(role) if role not in ("file", "motion") else f"the {role}")


def command_files(module, args) -> tuple[dict, dict, dict]:
    """(outputs, inputs, output folders) of a parsed command, by role."""
    def get(names: Iterable[str]) -> dict:
        return {n: getattr(args, n, None) for n in names}

    inputs = get(getattr(module, "INPUT_FILES", ()))
    implicit = getattr(module, "implicit_inputs", None)
    if implicit is not None:
        inputs.update(implicit(args))
    outputs = get(getattr(module, "OUTPUT_FILES", ()))
    implicit_out = getattr(module, "implicit_outputs", None)
    if implicit_out is not None:  # files an output brings along (a .gltf's .bin)
        outputs.update(implicit_out(args))
    return outputs, inputs, get(getattr(module, "OUTPUT_DIRS", ()))


def guard_command(module, args) -> None:
    """:func:`check_outputs` for a parsed command (what the CLI calls before ``run``)."""
    outputs, inputs, dirs = command_files(module, args)
    check_outputs(outputs, inputs, output_dirs=dirs)


__all__ = ["check_outputs", "command_files", "guard_command"]
