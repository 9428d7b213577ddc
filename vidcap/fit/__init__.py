"""2D pose by fitting the 10-cylinder body model to silhouettes (seed 004 section 3.1.4).

* :mod:`vidcap.fit.pose2d` - the fitting order of section 3.1.4 (an overview of the
  modules below) and the public names.
* :mod:`vidcap.fit.frame` - one frame's fit (fresh and warm recipes, the challenge).
* :mod:`vidcap.fit.tracking` - a clip: tracking, backward re-tracking, temporal priors.
* :mod:`vidcap.fit.state` - the frozen :class:`~vidcap.fit.state.FitState` and
  ``keep_if_better``; :mod:`vidcap.fit.engine` - the per-silhouette engine;
  :mod:`vidcap.fit.options` - :class:`~vidcap.fit.options.FitOptions`.
* The moves: :mod:`vidcap.fit.torso`, :mod:`vidcap.fit.limbs`, :mod:`vidcap.fit.legs`,
  :mod:`vidcap.fit.foreshortening`, :mod:`vidcap.fit.moves`, :mod:`vidcap.fit.grids`,
  :mod:`vidcap.fit.labels`; their candidates scored by :mod:`vidcap.fit.candidates`.
* :mod:`vidcap.fit.result` - :class:`FramePose`, :class:`Pose2D` and their file I/O.
* :mod:`vidcap.fit.raster` - batched rasteriser of posed 2D models (row spans);
  :mod:`vidcap.fit.normalise` - silhouette normalisation.
* :mod:`vidcap.fit.similarity` - S = exp(-p - n)(1 - p), Eq. 3.1-3.3.
* :mod:`vidcap.fit.search` - the coarse-to-fine interval search of Algorithms 1 and 6.
* :mod:`vidcap.fit.contour` - scan lines, elbow corner, knee crossing (Algorithms 2-5).
* :mod:`vidcap.fit.parallel` - a clip fitted in chunks on worker processes, limb labels
  reconciled across chunks.
* :mod:`vidcap.fit._kernels` - the compiled (numba) kernels behind raster and search
  (:mod:`vidcap.fit.modes`: the constants both read).

The public entry points are :func:`fit_pose` (one silhouette) and
:func:`fit_sequence` (a clip, returning :class:`Pose2D`). During 2D fitting ``l_*``
and ``r_*`` name image-left and image-right limbs, not the performer's sides.
"""

from vidcap.fit.pose2d import FramePose, Pose2D, fit_pose, fit_sequence

__all__ = ["FramePose", "Pose2D", "fit_pose", "fit_sequence"]
