"""The kinematic solve over a clip (issue 33): 2D joints -> BVH joint rotations.

Modules: :mod:`~vidcap.solve.skeleton` (parametrisation and forward kinematics),
:mod:`~vidcap.solve.limits` (joint limits), :mod:`~vidcap.solve.contact` (foot
contact), :mod:`~vidcap.solve.residuals` (residuals, sparse Jacobian),
:mod:`~vidcap.solve.gauss_newton` (the banded Levenberg-Marquardt),
:mod:`~vidcap.solve.signs` (depth signs and their confidence), :mod:`~vidcap.solve.clip`
(the whole solve).
"""

from vidcap.solve.clip import ClipSolve, solve_clip, solve_problem

__all__ = ["ClipSolve", "solve_clip", "solve_problem"]
