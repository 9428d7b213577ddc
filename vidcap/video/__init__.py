"""The video path: background, silhouettes, the 2D fit (``fit/``), lifting and the clip
solve (``solve/``), motion, and the pipeline that runs them in order."""
