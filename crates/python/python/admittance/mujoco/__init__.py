"""Experiment B on a plant this project did not write: MuJoCo (issue 15, part 3).

``python -m admittance.mujoco --urdf FILE [--base LINK] [--tip LINK] --out DIR [--contact push|wall]``

The arm's URDF is loaded into MuJoCo (meshes, visual and collision geometry stripped, the
arm's own inertials; joints off the base->tip chain fixed at 0, as the Rust loader locks
them) with joint friction, viscous damping and rotor armature that the controller and the
observers do not know, torque-controlled at 1 kHz, its angles read through a quantised,
noisy encoder. The controller, observers and admittance model are this package's, fed
what a real robot's driver gives: quantised angles and the torque commanded.

1. Free-motion data under PD + nominal gravity on a multi-sine inside the joint limits
   (and a second excitation for validation) train the learned observer's network, with and
   without friction-shaped inputs, and the hybrid observer's residual network.
2. The admittance experiment: joint 1 follows a slow sine; the hand is pushed by a scripted
   force (``xfrc_applied``, ``--contact push``) or meets a box (real MuJoCo contact,
   ``--contact wall``); the joint-space admittance model of experiment B, on joint 1, is
   driven by each variant's estimate (``learned``, ``learned_friction``, ``momentum``,
   ``hybrid``, ``oracle``) and a PD tracks the compliant reference.
3. The true external joint torque comes from MuJoCo itself: ``J^T f`` of the applied force
   at the hand, or the contact forces through the contact points' Jacobians.

``DIR`` is a run folder (docs/outputs.md) with ``"plant": "mujoco"``: ``admittance report
DIR`` draws its figures.
"""

from ._arms import robots_dir
from ._cosim import CosimConfig, run_cosimulation

__all__ = ["CosimConfig", "robots_dir", "run_cosimulation"]
