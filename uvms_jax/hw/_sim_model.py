"""The simulated arm's MuJoCo model: the robot's one MuJoCo body tree plus drives.

The bodies, joints, capsules and the tool site are :func:`uvms_jax.robot.add_robot`'s (with the
robot's mass properties where ``dynamics`` is on); this module adds what only the simulator
needs: gravity along the world's -z turned into the base frame (:func:`world_up`), no contacts,
rotor inertia and damping on every joint, the jaws (an arm with a gripper: the description's
fingers on their slide joints, the mimics tied to the gripper joint; or one slide joint at the
tool frame), and two
actuators per joint — a velocity servo ``v_<joint>`` and an integral-torque motor ``i_<joint>``
(:class:`~uvms_jax.hw.SimArm` drives both).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ._settings import SimSettings
from ._joints import MM_PER_M, JointSpec, joint_specs

if TYPE_CHECKING:
    import mujoco

__all__ = ["GRAVITY", "JAWS_BODY", "KV", "add_drives", "sim_spec", "world_up"]

_MM = 1.0 / MM_PER_M  # jaws: mm on the wire, m in MuJoCo

# Physics of the simulated device (not an arm's data): rotor inertia and damping per joint
# [kg·m², N·m·s/rad; jaws kg, N·s/m], the jaws' fingers box [m, kg] and the velocity servo gain.
_HINGE_ARMATURE, _HINGE_DAMPING = 0.05, 0.1
_JAWS_ARMATURE, _JAWS_DAMPING = 0.5, 1.0
_JAWS_HALF_SIZE, _JAWS_MASS = (0.01, 0.02, 0.02), 0.2
_GEOM_DENSITY = 1000.0  # [kg/m³] links without mass properties: capsules of water
KV = 30.0  # velocity servo gain [N·m·s/rad; N·s/m]
GRAVITY = 9.81  # [m/s²]
JAWS_BODY = "jaws"  # the body the jaws' slide joint moves


def world_up(base_rpy: Sequence[float] = SimSettings.base_rpy) -> np.ndarray:
    """(3,) unit vector of the world's up (+z) in the arm's base frame, ``R^T e_z`` for the base
    orientation R = Rz(yaw) Ry(pitch) Rx(roll) of ``base_rpy`` (URDF roll, pitch, yaw [rad]).

    Gravity acts along minus this vector, buoyancy along it; (0, 0, 0) gives exactly
    (0, 0, 1) (the upright base), (π, 0, 0) about (0, 0, -1) (the base hanging).
    """
    import mujoco  # imported here: the protocol layer must not need MuJoCo

    q = np.zeros(4)
    mujoco.mju_euler2Quat(q, np.asarray(base_rpy, dtype=float), "XYZ")  # URDF rpy: extrinsic x, y, z
    mujoco.mju_negQuat(q, q)  # the inverse rotation: world → base
    up = np.zeros(3)
    mujoco.mju_rotVecQuat(up, np.array([0.0, 0.0, 1.0]), q)
    return up


def massive_bodies(robot) -> set[int]:
    """Body numbers of ``robot`` (``-1`` base, ``i`` link of joint i) that carry mass properties."""
    return {b.body for b in robot.inertials if b.mass > 0}


def sim_spec(robot, kv: float = KV, physics_dt: float = SimSettings.physics_dt, dynamics: bool = True,
             base_rpy: Sequence[float] = SimSettings.base_rpy) -> mujoco.MjSpec:
    """MuJoCo model of the simulated ``robot`` with its base fixed: its body tree
    (:func:`uvms_jax.robot.add_robot`) with the drives of :func:`add_drives`.

    MuJoCo's world is the arm's base frame; nothing collides. With ``dynamics`` each link
    carries the robot's mass properties (``robot.inertials``, summed per body) under gravity
    along the world's -z (:func:`world_up`: the base's -z when upright); buoyancy is applied by
    :class:`~uvms_jax.hw.SimArm`.

    Args:
      robot: the arm (:class:`uvms_jax.robot.Robot`).
      kv: velocity actuator gain [N·m·s/rad; N·s/m for the jaws].
      physics_dt: time step [s].
      dynamics: the robot's mass properties, gravity on.
      base_rpy: orientation of the base in the world, URDF roll, pitch, yaw [rad]
        (:attr:`SimSettings.base_rpy`); it sets the gravity vector.

    Returns:
      an uncompiled ``mujoco.MjSpec`` (``.compile()`` gives the ``MjModel``).
    """
    import mujoco  # imported here: the protocol layer must not need MuJoCo

    from uvms_jax.robot import add_robot

    spec = mujoco.MjSpec()
    spec.modelname = f"{robot.name}_hw_sim"
    spec.compiler.degree = False
    spec.default.geom.contype, spec.default.geom.conaffinity, spec.default.geom.density = 0, 0, _GEOM_DENSITY
    add_robot(spec, robot, inertial=bool(massive_bodies(robot)) and dynamics, finger_joints=bool(robot.fingers))
    spec.option.timestep = physics_dt
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.gravity = -GRAVITY * world_up(base_rpy)
    return add_drives(spec, robot, kv, dynamics)


def add_drives(spec: mujoco.MjSpec, robot, kv: float = KV, dynamics: bool = True) -> mujoco.MjSpec:
    """Add what the simulated device needs to the model ``spec`` holding ``robot``'s body tree
    (as :func:`uvms_jax.robot.add_robot` names it; anywhere in the world, e.g. under a vehicle):
    the jaws' slide joint (an arm with a gripper), and a velocity actuator and an integral-torque
    motor on every joint. Where the body tree holds the description's fingers on their joints
    (``add_robot(..., finger_joints=True)``), the gripper joint's finger is the jaws and each mimic
    follows it by a joint equality (``finger = multiplier · opening + offset``); otherwise the
    jaws are a slide body at the tool frame.

    Bodies without mass properties (all of them without ``dynamics``, or for an arm whose
    description has none, e.g. the Reach Alpha 5) are gravity compensated: such an arm is
    servoed kinematically, weightless. The jaws (a slide body at the tool frame, opening along
    its x axis; a 0.2 kg box) are light and gravity compensated either way. Position limits are
    the hardware path's (:func:`~uvms_jax.hw.joint_specs`: rad; the jaws' mm as m); every joint
    gets the device's rotor inertia and damping.

    Returns:
      ``spec``, changed in place.
    """
    import mujoco

    from uvms_jax.robot import base_body

    specs = joint_specs(robot)
    massive = massive_bodies(robot) if dynamics else set()
    for k, name in enumerate(robot.link_names):
        spec.body(name).gravcomp = 0.0 if k in massive else 1.0
    spec.body(base_body(robot)).gravcomp = 0.0 if -1 in massive else 1.0
    jaws = robot.gripper is not None  # the last spec is the jaws
    for j in specs[:-1] if jaws else specs:
        joint = spec.joint(j.name)
        joint.range = [j.lower, j.upper]
        joint.armature = _HINGE_ARMATURE
        joint.damping[0] = _HINGE_DAMPING  # [linear, (polynomial terms)]
    if jaws and robot.fingers and spec.joint(specs[-1].name) is not None:
        _tie_fingers(spec, robot, specs[-1])
    elif jaws:
        _add_jaws(spec, robot, specs[-1])
    for j in specs:
        act = spec.add_actuator(name=f"v_{j.name}", target=j.name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_velocity(kv=kv)
        spec.add_actuator(name=f"i_{j.name}", target=j.name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    return spec


def _tie_fingers(spec: mujoco.MjSpec, robot, jaws_spec) -> None:
    """The description's fingers as the jaws: the gripper joint driven (the hardware path's
    limits, the device's rotor inertia and damping), every other finger tied to it."""
    import mujoco

    for f in robot.fingers:
        spec.body(f.link).gravcomp = 1.0
        joint = spec.joint(f.joint)
        joint.armature = _JAWS_ARMATURE
        joint.damping[0] = _JAWS_DAMPING
        if f.joint == jaws_spec.name:
            joint.range = [jaws_spec.lower * _MM, jaws_spec.upper * _MM]
            continue
        tie = spec.add_equality(type=mujoco.mjtEq.mjEQ_JOINT, objtype=mujoco.mjtObj.mjOBJ_JOINT, name1=f.joint,
                                name2=jaws_spec.name)
        tie.data[:5] = [f.offset, f.multiplier, 0.0, 0.0, 0.0]  # joint1 = offset + multiplier · joint2


def _add_jaws(spec: mujoco.MjSpec, robot, jaws: JointSpec) -> None:
    """The jaws: a light slide body at the tool frame, opening along its x axis (limits: the
    spec's mm as m)."""
    import mujoco

    from uvms_jax.robot import TOOL_SITE

    tool = spec.site(TOOL_SITE)
    body = spec.body(robot.link_names[-1]).add_body(name=JAWS_BODY, pos=tool.pos, quat=tool.quat, gravcomp=1.0)
    body.add_joint(name=jaws.name, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1.0, 0.0, 0.0],
                   range=[jaws.lower * _MM, jaws.upper * _MM], limited=mujoco.mjtLimited.mjLIMITED_TRUE,
                   armature=_JAWS_ARMATURE, damping=_JAWS_DAMPING)
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=_JAWS_HALF_SIZE, mass=_JAWS_MASS)
