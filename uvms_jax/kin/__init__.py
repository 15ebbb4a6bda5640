"""Kinematics of serial chains in product-of-exponentials (POE) form.

Conventions (written once, used everywhere):

- Frames: every pose ``T_a_b`` is the pose of frame b in frame a, a ``(..., 4, 4)``
  homogeneous matrix; positions in metres, angles in radians (jaws in metres).
- Twists are ``[v, ω]``: linear part first. A revolute joint with unit axis ω through the
  point q has ``ξ = [−ω × q, ω]``; a prismatic joint along k has ``ξ = [k, 0]``.
- FK: ``T_base_tool(q) = exp(ξ̂1 q1) ⋯ exp(ξ̂n qn) T_base_tool0``.
- Geometric Jacobian ``(..., 6, n)``: rows (linear velocity of the tool point, angular
  velocity), both in the base frame. The spatial-twist Jacobian has the spatial twists
  ``ξ'_i`` as columns.
- Every public function accepts any leading batch shape, works under ``jit``/``vmap`` and
  computes in the dtype of its input (float32 by default, float64 when x64 is enabled).

Robots: the papers' models (``docking_arm``, ``uvms12``, ``bravo7``) and any arm on a vehicle
(``uvms``); any arm from a file is read by :mod:`uvms_jax.robot` (``robot.chain_from_urdf``,
``robot.chain_from_mjcf``, ``robot.load_robot``), built from this package's ``make_chain``;
see docs/robots.md.
"""

from uvms_jax.kin._chain import Chain
from uvms_jax.kin._chain import chain_from_urdf_joints
from uvms_jax.kin._chain import check_joint_array
from uvms_jax.kin._chain import make_chain
from uvms_jax.kin._chain import prismatic_twist
from uvms_jax.kin._chain import revolute_twist
from uvms_jax.kin._chain import with_dtype
from uvms_jax.kin._export import bravo7_urdf
from uvms_jax.kin._export import to_urdf
from uvms_jax.kin._fk import Kinematics
from uvms_jax.kin._fk import fk
from uvms_jax.kin._fk import fk_of
from uvms_jax.kin._fk import pose_and_jacobian_of
from uvms_jax.kin._fk import jacobian
from uvms_jax.kin._fk import jacobian_rows
from uvms_jax.kin._fk import kinematics
from uvms_jax.kin._fk import pose_and_jacobian_rows
from uvms_jax.kin._fk import spatial_jacobian
from uvms_jax.kin._fk import spatial_jacobian_rows
from uvms_jax.kin._ik import IKSolutions
from uvms_jax.kin._ik import dls_ik
from uvms_jax.kin._ik import dls_step
from uvms_jax.kin._ik import spd_solve
from uvms_jax.kin._ik import elbow_branch_scalars
from uvms_jax.kin._ik import elbow_branches
from uvms_jax.kin._ik import elbow_ik
from uvms_jax.kin._ik import numeric_ik
from uvms_jax.kin._ik import reaches
from uvms_jax.kin._ik import reaches_scalars
from uvms_jax.kin._ik import wrap_into_limits
from uvms_jax.kin._lie import axis_rotation
from uvms_jax.kin._lie import matmul
from uvms_jax.kin._lie import matvec
from uvms_jax.kin._lie import pose_inverse
from uvms_jax.kin._models import BRAVO7_JOINTS
from uvms_jax.kin._models import bravo7
from uvms_jax.kin._models import bravo7_inertials
from uvms_jax.kin._models import docking_arm
from uvms_jax.kin._models import uvms12
from uvms_jax.kin._vehicle import VEHICLE_DOFS
from uvms_jax.kin._vehicle import adjoint_twists
from uvms_jax.kin._vehicle import uvms
from uvms_jax.urdf import PRISMATIC
from uvms_jax.urdf import REVOLUTE
from uvms_jax.urdf import UrdfJoint
