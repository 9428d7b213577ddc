"""The kinds of candidate a compiled search scores (read by :mod:`vidcap.video.fit.raster`,
:mod:`vidcap.video.fit._kernels` and the fit's moves; one place, so neither imports the other).

A limb segment's distal end moved by an angle or a length ratio (its children
follow), or a whole pose in which each value sets some angles, the torso about the
neck, some foreshortening ratios (scaled, at most 1) or the lateral spread.
"""

SEARCH_LIMB_ANGLE, SEARCH_LIMB_RATIO = 0, 1
SEARCH_POSE_ANGLES, SEARCH_POSE_TORSO_NECK, SEARCH_POSE_FORE, SEARCH_POSE_SPREAD = 2, 3, 4, 5
