"""Skeletons, motions and forward kinematics, shared by BVH, ASF/AMC and both paths.

A :class:`Skeleton` is a joint tree with rest offsets; a :class:`Motion` is a root
trajectory plus one local rotation per joint and frame. Rotations are stored as
unit quaternions in scipy's scalar-last order ``(x, y, z, w)``.

Convention: a joint's *local* rotation rotates everything below it; the world
rotation of joint j is ``R_parent(j) @ L_j`` and its world position is
``p_parent(j) + R_parent(j) @ offset_j``. This is the BVH convention.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np
from scipy.spatial.transform import Rotation


@dataclass(frozen=True)
class Skeleton:
    """A joint hierarchy with rest-pose offsets.

    Parameters
    ----------
    joint_names : tuple of str, length J
        Unique joint names.
    parents : tuple of int, length J
        Index of each joint's parent, -1 for the root (joint 0). Parents come before
        their children.
    offsets : numpy.ndarray, shape (J, 3)
        Rest offset of each joint from its parent, metres (the root's is added to
        the root position).
    end_sites : mapping of str to numpy.ndarray (3,), optional
        End Site offsets (metres) of leaf joints, by joint name.
    """

    joint_names: tuple[str, ...]
    parents: tuple[int, ...]
    offsets: np.ndarray
    end_sites: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))

    def __post_init__(self):
        names = tuple(self.joint_names)
        parents = tuple(int(p) for p in self.parents)
        offsets = np.asarray(self.offsets, dtype=float).reshape(len(names), 3)
        if len(set(names)) != len(names):
            raise ValueError("joint names must be unique")
        if len(parents) != len(names) or parents[0] != -1:
            raise ValueError("parents must have one entry per joint and joint 0 must be the root")
        if any(not (0 <= p < j) for j, p in enumerate(parents) if j > 0):
            raise ValueError("every parent must come before its child")
        offsets.setflags(write=False)
        ends = {k: np.asarray(v, dtype=float).reshape(3) for k, v in dict(self.end_sites).items()}
        unknown = set(ends) - set(names)
        if unknown:
            raise ValueError(f"end sites on unknown joints: {sorted(unknown)}")
        object.__setattr__(self, "joint_names", names)
        object.__setattr__(self, "parents", parents)
        object.__setattr__(self, "offsets", offsets)
        object.__setattr__(self, "end_sites", MappingProxyType(ends))

    @property
    def n_joints(self) -> int:
        """Number of joints J."""
        return len(self.joint_names)

    def index(self, name: str) -> int:
        """Index of joint ``name``."""
        try:
            return self.joint_names.index(name)
        except ValueError:
            raise KeyError(f"no joint named {name!r}") from None

    def children(self, j: int) -> list[int]:
        """Indices of the children of joint ``j``."""
        return [k for k, p in enumerate(self.parents) if p == j]

    def rest_positions(self) -> np.ndarray:
        """World positions of the joints in the rest pose (root at its offset), (J, 3) m."""
        pos = np.zeros((self.n_joints, 3))
        for j, p in enumerate(self.parents):
            pos[j] = self.offsets[j] if p < 0 else pos[p] + self.offsets[j]
        return pos

    def scaled(self, factor: float) -> Skeleton:
        """The same skeleton with every offset multiplied by ``factor``."""
        return Skeleton(
            self.joint_names,
            self.parents,
            self.offsets * factor,
            {k: v * factor for k, v in self.end_sites.items()},
        )


@dataclass(frozen=True)
class Motion:
    """A skeleton moving over F frames.

    Parameters
    ----------
    skeleton : Skeleton
        The joint hierarchy (J joints).
    root_positions : numpy.ndarray, shape (F, 3)
        Root translation per frame, metres (added to the root's offset).
    rotations : numpy.ndarray, shape (F, J, 4)
        Local joint rotations as unit quaternions (x, y, z, w).
    fps : float
        Frames per second.
    """

    skeleton: Skeleton
    root_positions: np.ndarray
    rotations: np.ndarray
    fps: float

    def __post_init__(self):
        root = np.asarray(self.root_positions, dtype=float)
        rot = np.asarray(self.rotations, dtype=float)
        if root.ndim != 2 or root.shape[1] != 3:
            raise ValueError(f"root_positions must be (F, 3), got {root.shape}")
        if rot.shape != (root.shape[0], self.skeleton.n_joints, 4):
            raise ValueError(
                f"rotations must be (F, J, 4) = ({root.shape[0]}, {self.skeleton.n_joints}, 4),"
                f" got {rot.shape}"
            )
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise ValueError(f"fps must be positive, got {self.fps!r}")
        object.__setattr__(self, "root_positions", root)
        object.__setattr__(self, "rotations", rot)
        object.__setattr__(self, "fps", float(self.fps))

    @property
    def n_frames(self) -> int:
        """Number of frames F."""
        return self.root_positions.shape[0]

    @classmethod
    def rest(cls, skeleton: Skeleton, n_frames: int = 1, fps: float = 30.0) -> Motion:
        """A motion holding the rest pose for ``n_frames`` frames."""
        rot = np.zeros((n_frames, skeleton.n_joints, 4))
        rot[..., 3] = 1.0
        return cls(skeleton, np.zeros((n_frames, 3)), rot, fps)

    def world_transforms(self) -> tuple[np.ndarray, np.ndarray]:
        """World rotation matrices and positions of every joint.

        Returns
        -------
        rotations : numpy.ndarray, shape (F, J, 3, 3)
            World rotation of each joint's frame.
        positions : numpy.ndarray, shape (F, J, 3)
            World position of each joint, metres.
        """
        F, J = self.n_frames, self.skeleton.n_joints
        local = Rotation.from_quat(self.rotations.reshape(-1, 4)).as_matrix().reshape(F, J, 3, 3)
        world_r = np.empty_like(local)
        world_p = np.empty((F, J, 3))
        off = self.skeleton.offsets
        for j, p in enumerate(self.skeleton.parents):  # loop over joints, vectorised over frames
            if p < 0:
                world_r[:, j] = local[:, j]
                world_p[:, j] = self.root_positions + off[j]
            else:
                world_r[:, j] = world_r[:, p] @ local[:, j]
                world_p[:, j] = world_p[:, p] + world_r[:, p] @ off[j]
        return world_r, world_p

    def positions(self) -> np.ndarray:
        """Forward kinematics: world joint positions, shape (F, J, 3), metres."""
        return self.world_transforms()[1]

    def end_site_positions(self) -> dict[str, np.ndarray]:
        """World positions of the End Sites, by joint name, each (F, 3) metres."""
        world_r, world_p = self.world_transforms()
        out = {}
        for name, off in self.skeleton.end_sites.items():
            j = self.skeleton.index(name)
            out[name] = world_p[:, j] + world_r[:, j] @ off
        return out

    def resampled(self, fps: float, *, times=None) -> Motion:
        """This motion resampled to ``fps``: root linearly, rotations by slerp.

        Parameters
        ----------
        fps : float
            The new frame rate.
        times : array_like, shape (F,), optional
            When each frame was taken, seconds, increasing (a variable-rate video's
            timestamps); default ``arange(F) / self.fps``. The new frames are evenly
            spaced from the first time to the last.
        """
        from scipy.spatial.transform import Slerp

        if times is None:
            t_old = np.arange(self.n_frames) / self.fps
        else:
            t_old = np.asarray(times, dtype=float)
            if t_old.shape != (self.n_frames,) or (np.diff(t_old) <= 0).any():
                raise ValueError(f"times must be ({self.n_frames},) and increasing")
        duration = t_old[-1] - t_old[0]
        n_new = int(np.floor(duration * fps + 1e-9)) + 1
        t_new = np.minimum(t_old[0] + np.arange(n_new) / fps, t_old[-1])  # no rounding past
        root = np.stack([np.interp(t_new, t_old, self.root_positions[:, k]) for k in range(3)], 1)
        rot = np.empty((n_new, self.skeleton.n_joints, 4))
        if self.n_frames == 1:
            rot[:] = self.rotations[0]
        else:
            for j in range(self.skeleton.n_joints):
                slerp = Slerp(t_old, Rotation.from_quat(self.rotations[:, j]))
                rot[:, j] = slerp(t_new).as_quat()
        return Motion(self.skeleton, root, rot, fps)

    def frames(self, start: int, stop: int) -> Motion:
        """Frames ``start`` (inclusive) to ``stop`` (exclusive)."""
        return Motion(
            self.skeleton,
            self.root_positions[start:stop],
            self.rotations[start:stop],
            self.fps,
        )
