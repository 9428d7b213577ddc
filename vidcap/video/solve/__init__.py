"""The kinematic solve over a clip (issue 33): 2D joints -> BVH joint rotations.

Modules: :mod:`~vidcap.video.solve.skeleton` (parametrisation and forward kinematics),
:mod:`~vidcap.video.solve.limits` (joint limits), :mod:`~vidcap.video.solve.contact` (foot
contact), :mod:`~vidcap.video.solve.noise` (the 2D joints' noise, the noise-robust
scale), :mod:`~vidcap.video.solve.residuals` (residuals, sparse Jacobian),
:mod:`~vidcap.video.solve.gauss_newton` (the banded Levenberg-Marquardt) on
:mod:`~vidcap.video.solve.blocksolve` (LAPACK's banded Cholesky),
:mod:`~vidcap.video.solve.signs` (depth signs and their confidence),
:mod:`~vidcap.video.solve.repair` (outlier frames re-started), :mod:`~vidcap.video.solve.prior`
(the pose prior learned from motion capture), :mod:`~vidcap.video.solve.clip` (the whole solve).
"""

from vidcap.video.solve.clip import ClipSolve, solve_clip, solve_problem

__all__ = ["ClipSolve", "solve_clip", "solve_problem"]
