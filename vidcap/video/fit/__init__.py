"""2D pose by fitting the 10-cylinder body model to silhouettes (seed 004 section 3.1.4).

* :mod:`vidcap.video.fit.pose2d` - the fitting order of section 3.1.4 (an overview of the
  modules below) and the public names.
* :mod:`vidcap.video.fit.frame` - one frame's fit (fresh and warm recipes, the challenge).
* :mod:`vidcap.video.fit.tracking` - a clip: tracking, backward re-tracking, temporal priors.
* :mod:`vidcap.video.fit.state` - the frozen :class:`~vidcap.video.fit.state.FitState` and
  ``keep_if_better``; :mod:`vidcap.video.fit.engine` - the per-silhouette engine;
  :mod:`vidcap.video.fit.options` - :class:`~vidcap.video.fit.options.FitOptions`.
* The moves: :mod:`vidcap.video.fit.torso`, :mod:`vidcap.video.fit.limbs`,
  :mod:`vidcap.video.fit.legs`, :mod:`vidcap.video.fit.foreshortening`,
  :mod:`vidcap.video.fit.moves`, :mod:`vidcap.video.fit.grids`,
  :mod:`vidcap.video.fit.labels`; their candidates scored by :mod:`vidcap.video.fit.candidates`.
* :mod:`vidcap.video.fit.result` - :class:`FramePose`, :class:`Pose2D` and their file I/O.
* :mod:`vidcap.video.fit.raster` - batched rasteriser of posed 2D models (row spans);
  :mod:`vidcap.video.fit.normalise` - silhouette normalisation.
* :mod:`vidcap.video.fit.similarity` - S = exp(-p - n)(1 - p), Eq. 3.1-3.3.
* :mod:`vidcap.video.fit.search` - the coarse-to-fine interval search of Algorithms 1 and 6.
* :mod:`vidcap.video.fit.contour` - scan lines, elbow corner, knee crossing (Algorithms 2-5).
* :mod:`vidcap.video.fit.parallel` - a clip fitted in chunks on worker processes, limb labels
  reconciled across chunks.
* :mod:`vidcap.video.fit._kernels` - the compiled (numba) kernels behind raster and search
  (:mod:`vidcap.video.fit.modes`: the constants both read).

The public entry points are :func:`fit_pose` (one silhouette) and
:func:`fit_sequence` (a clip, returning :class:`Pose2D`). During 2D fitting ``l_*``
and ``r_*`` name image-left and image-right limbs, not the performer's sides.
"""

from vidcap.video.fit.pose2d import FramePose, Pose2D, fit_pose, fit_sequence

__all__ = ["FramePose", "Pose2D", "fit_pose", "fit_sequence"]
