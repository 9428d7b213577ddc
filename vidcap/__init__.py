"""vidcap: single-camera video to BVH motion, and joint centres from marker C3D."""

__version__ = "0.1.0"

from vidcap.errors import VidcapError  # noqa: E402

__all__ = ["VidcapError", "__version__"]
