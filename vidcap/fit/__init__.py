"""2D pose by fitting the 10-cylinder body model to silhouettes (seed 004 section 3.1.4).

* :mod:`vidcap.fit.raster` - batched rasteriser of posed 2D models (row spans),
  silhouette normalisation.
* :mod:`vidcap.fit.similarity` - S = exp(-p - n)(1 - p), Eq. 3.1-3.3.
* :mod:`vidcap.fit.search` - the coarse-to-fine interval search of Algorithms 1 and 6.
* :mod:`vidcap.fit.contour` - scan lines, elbow corner, knee crossing (Algorithms 2-5).
* :mod:`vidcap.fit.pose2d` - the fitting order of section 3.1.4, tracking, confidence.
* :mod:`vidcap.fit.parallel` - a clip fitted in chunks on worker processes, limb labels
  reconciled across chunks.
* :mod:`vidcap.fit._kernels` - the compiled (numba) kernels behind raster and search.

The public entry points are :func:`fit_pose` (one silhouette) and
:func:`fit_sequence` (a clip, returning :class:`Pose2D`). During 2D fitting ``l_*``
and ``r_*`` name image-left and image-right limbs, not the performer's sides.
"""

from vidcap.fit.pose2d import FramePose, Pose2D, fit_pose, fit_sequence

__all__ = ["FramePose", "Pose2D", "fit_pose", "fit_sequence"]
