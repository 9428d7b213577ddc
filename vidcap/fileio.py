"""Small file helpers shared by every stage: atomic writes and progress bars."""

from __future__ import annotations

import contextlib
import glob
import os
import sys
import tempfile
import zipfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from vidcap import interrupt


def check_output_file(path: str | os.PathLike, inputs=()) -> None:
    """Raise a one-line error now if ``path`` cannot be written as an output file.

    Commands call this before any work, so a typo in ``-o`` costs nothing: the path
    is a folder, or lies under a file, or is one of the command's ``inputs`` (writing
    a BVH over the video it came from), or its folder cannot be written.

    Parameters
    ----------
    path : str or path-like
        The output file.
    inputs : iterable of str or path-like
        The command's input files (``None`` entries are skipped).

    Raises
    ------
    vidcap.errors.UsageError
    """
    from vidcap.errors import UsageError

    p = Path(path)
    if p.is_dir():
        raise UsageError("is a folder: give a file name to write", path)
    for src in inputs:
        if src is not None and p.exists() and Path(src).exists() and p.samefile(src):
            raise UsageError("is also an input of this command: writing it would destroy "
                             "the input", path)
    folder = p.absolute().parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent  # atomic_path creates the missing folders
    if not folder.is_dir():
        raise UsageError(f"cannot write here: {folder} is a file, not a folder", path)
    if not os.access(folder, os.W_OK | os.X_OK):
        raise UsageError(f"cannot write here: no permission to write in {folder}", path)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` on success.

    A failure inside the ``with`` block removes the temporary file and leaves any
    existing ``path`` untouched, so an output is either complete or absent.

    Parameters
    ----------
    path : str or path-like
        The final output file.
    suffix : str, optional
        Suffix of the temporary file (defaults to ``path``'s own suffix, which lets
        writers that pick a format from the name, such as FFmpeg, still do so).
    """
    final = Path(path)
    check_output_file(final)
    final.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(
        prefix=f".{final.name}.", suffix=final.suffix if suffix is None else suffix,
        dir=final.parent,
    )
    os.close(fd)
    tmp_path = Path(tmp)
    interrupt.temporaries.add(tmp)  # removed even when an interrupt cannot unwind
    # mkstemp creates the file 0600; give the output the permissions any new file
    # would get (0666 less the umask), as users expect of files they asked for.
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp_path, 0o666 & ~umask)
    try:
        yield tmp_path
        os.replace(tmp_path, final)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()
        interrupt.temporaries.discard(tmp)


def remove_atomic_leftovers(path: str | os.PathLike) -> list[Path]:
    """Delete the temporary files :func:`atomic_path` left beside ``path``.

    A process killed while writing (SIGKILL, a lost cluster worker) cannot clean up;
    call this once nothing can be writing ``path`` any more.

    Returns
    -------
    list of Path
        The files removed.
    """
    final = Path(path)
    removed = []
    for tmp in final.parent.glob(f".{glob.escape(final.name)}.*"):
        with contextlib.suppress(OSError):
            tmp.unlink()
            removed.append(tmp)
    return removed


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def savez_atomic(path: str | os.PathLike, **arrays) -> None:
    """``numpy.savez_compressed`` to ``path`` atomically.

    A value with a ``frame_shape`` (a :class:`vidcap.video.masks.MaskStack`) is written as
    its full (F, H, W) bool array one frame at a time, so it never sits in memory
    whole; ``numpy.load`` reads it back as an ordinary array.
    """
    from numpy.lib import format as npy

    with atomic_path(path, suffix=".npz") as tmp:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED,
                             allowZip64=True) as zf:
            for name, value in arrays.items():
                with zf.open(f"{name}.npy", "w", force_zip64=True) as fh:
                    if hasattr(value, "frame_shape"):
                        header = {"descr": npy.dtype_to_descr(np.dtype(bool)),
                                  "fortran_order": False, "shape": tuple(value.shape)}
                        npy.write_array_header_2_0(fh, header)
                        for k in range(len(value)):
                            fh.write(np.ascontiguousarray(value[k], dtype=bool).tobytes())
                    else:
                        npy.write_array(fh, np.asanyarray(value), allow_pickle=True)


def progress(iterable=None, *, total=None, desc: str = "", unit: str = "it", enabled=None):
    """A tqdm progress bar on stderr, silent when stderr is not a terminal.

    ``enabled`` forces it on or off; set ``VIDCAP_PROGRESS=1`` to force it on.
    """
    from tqdm.auto import tqdm

    if enabled is None:
        enabled = sys.stderr.isatty() or os.environ.get("VIDCAP_PROGRESS") == "1"
    return tqdm(
        iterable, total=total, desc=desc, unit=unit, disable=not enabled,
        file=sys.stderr, dynamic_ncols=True, leave=False,
    )
