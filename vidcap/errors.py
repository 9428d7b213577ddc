"""Errors a user can cause.

Every error a user can provoke (a bad file, a bad option, a malformed annotation)
raises a :class:`VidcapError` subclass whose message names the file and what to do.
The CLI prints it as one line ``vidcap: error: <file>: <problem>`` and exits with 2.
"""

from __future__ import annotations

from os import PathLike


class VidcapError(Exception):
    """Base class for errors caused by user input.

    Parameters
    ----------
    message : str
        What is wrong and, where it helps, what to do about it.
    path : str or path-like, optional
        The file the problem is in. It is prefixed to the message.
    """

    def __init__(self, message: str, path: str | PathLike | None = None):
        self.path = None if path is None else str(path)
        self.problem = message
        super().__init__(f"{self.path}: {message}" if self.path else message)


class InputFileError(VidcapError):
    """An input file is missing, unreadable or malformed."""


class VideoError(InputFileError):
    """A video file cannot be decoded (empty, truncated, not a video, no video stream)."""


class MotionFileError(InputFileError):
    """A BVH, ASF or AMC file is malformed."""


class C3DError(InputFileError):
    """A C3D file cannot be parsed or lacks what is needed."""


class AnnotationError(InputFileError):
    """An annotations JSON file is malformed or refers to unknown segments/frames."""


class FitError(VidcapError):
    """A fit cannot be made from the data given (too few points, nothing moved...)."""


class UsageError(VidcapError):
    """A command-line option or argument is invalid."""


class BackgroundError(VidcapError):
    """The background cannot be estimated from the video given."""
