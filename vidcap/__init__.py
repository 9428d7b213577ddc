"""vidcap: single-camera video to BVH or glTF motion, and joint centres from marker C3D.

>>> import vidcap                                           # doctest: +SKIP
>>> motion = vidcap.convert("walk.mp4", height=1.80)        # doctest: +SKIP
>>> motion.save("walk.glb", rig="mixamo")                   # doctest: +SKIP
>>> centres = vidcap.joints("trial.c3d")                    # doctest: +SKIP
"""

__version__ = "0.1.0"

from vidcap.api import JointCentres, VideoMotion, convert, joints  # noqa: E402
from vidcap.errors import VidcapError  # noqa: E402

__all__ = ["JointCentres", "VidcapError", "VideoMotion", "__version__", "convert", "joints"]
