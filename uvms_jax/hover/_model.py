"""The hovering vehicle's MuJoCo model: a hull on a free joint, the arm fixed under it, thrusters.

What MuJoCo gives: rigid-body dynamics of the vehicle and the arm together (the arm's motion
moves the vehicle), gravity, and drag from its inertia-box fluid model (``<option density
viscosity wind>``; every body moves through the water as the box with its mass and inertia,
with a quadratic drag ``½ ρ A |v| v`` per face and a small linear viscous term; ``wind`` is the
water current). What it does not give, and this package adds: buoyancy
(:func:`~uvms_jax.hover.buoyancy_xfrc` on the bodies of :func:`buoyancy_bodies`, applied each
physics step), and the thrusters' commands (:mod:`uvms_jax.hover._control`). No added mass: the
inertia-box model has none, and adding it as forces from the acceleration would make the
equations implicit; the model accelerates faster than a real hull, whose added mass is of the
order of tens of per cent of its displaced mass per axis (docs/hover.md).

Names in the model: the vehicle body and its free joint ``vehicle``, the hull box ``hull``,
one site and one actuator per thruster ``thruster_<k>`` (a motor along the thruster's
direction, control = thrust [N] within ±max), a position servo ``servo_<joint>`` per arm joint
(control = the joint target [rad]) and the arm's bodies, joints and tool site as
:func:`uvms_jax.robot.add_robot` names them. Nothing collides.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import mujoco
import numpy as np

from uvms_jax import frames
from uvms_jax.robot import BASE, Robot, add_robot, base_body

from ._hydro import buoyancy_xfrc
from ._settings import VehicleSettings

__all__ = ["HULL_GEOM", "SERVO_KP", "SERVO_KV", "VEHICLE_BODY", "apply_buoyancy", "buoyancy_bodies", "hover_mjcf",
           "hover_model", "hover_spec", "servo_name", "thruster_name", "trimmed"]

VEHICLE_BODY = "vehicle"  # the hull's body and its free joint
HULL_GEOM = "hull"
# The arm's position servos: stiff enough that the Bravo 7's weight in water (about 42 N, up to
# 0.5 m out) bends a joint by under 0.002 rad, well inside the executor's 0.01 rad gate; kv damps
# every joint at least critically (the base and shoulder joints move ~0.8 kg·m² with the
# armature: damping ratio ~1.2).
SERVO_KP = 5000.0  # [N·m/rad]
SERVO_KV = 150.0  # [N·m·s/rad]
# Rotor inertia and viscous friction of each arm joint [kg·m², N·m·s/rad]: the values of the
# simulated arm (uvms_jax.hw); they keep the light wrist links from stiffening the step.
_ARMATURE, _DAMPING = 0.05, 0.1
# Density [kg/m³] of arm links the description gives no mass for: their capsules at the density
# of water, lifted at their centres of mass (neutral, as the hardware simulator treats them).
_GEOM_DENSITY = 1000.0


def thruster_name(k: int) -> str:
    """Site and actuator name of thruster ``k``."""
    return f"thruster_{k}"


def servo_name(joint: str) -> str:
    """Actuator name of the position servo on arm joint ``joint``."""
    return f"servo_{joint}"


def _hull_inertia(vehicle: VehicleSettings) -> np.ndarray:
    """(3,) principal inertia [kg·m²] of the uniform hull box about its centre."""
    a, b, c = vehicle.size
    return vehicle.mass / 12.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])


def hover_spec(robot: Robot | None, vehicle: VehicleSettings = VehicleSettings(), *,
               xyz: Sequence[float] = (0.0, 0.0, 0.0), rpy: Sequence[float] = (0.0, 0.0, 0.0),
               current: Sequence[float] = (0.0, 0.0, 0.0), physics_dt: float = 0.002,
               servos: bool = True) -> mujoco.MjSpec:
    """The model of the vehicle hovering in open water, the arm (if any) hanging at its mount.

    Args:
      robot: the arm (its mass properties go in; an arm without them gets capsules at the
        density of water), or None for the hull alone.
      vehicle: hull, water and thrusters.
      xyz, rpy: the vehicle's initial pose in the world (its free joint's ``qpos0``): V's
        origin [m] and URDF roll, pitch, yaw [rad] — e.g. a docking pose.
      current: the water's velocity at the start [m/s] (``opt.wind``; a simulator changes it
        over time).
      physics_dt: MuJoCo's time step [s].
      servos: a position servo on every arm joint; False: none, for a simulator that adds its
        own drives (the hardware runner's simulated arm, :class:`~uvms_jax.hover.HoverWorld`).

    Returns:
      an uncompiled ``mujoco.MjSpec`` (``.compile()``: :func:`hover_model`; ``.to_xml()``:
      :func:`hover_mjcf`).
    """
    if not physics_dt > 0:
        raise ValueError(f"physics_dt must be > 0 [s], got {physics_dt}")
    spec = mujoco.MjSpec()
    spec.modelname = f"hover_{robot.name if robot is not None else 'hull'}"
    spec.compiler.degree = False
    o = spec.option
    o.timestep, o.integrator, o.gravity = physics_dt, mujoco.mjtIntegrator.mjINT_IMPLICITFAST, [0.0, 0.0, -vehicle.gravity]
    o.density, o.viscosity, o.wind = vehicle.water_density, vehicle.viscosity, current
    spec.default.geom.contype, spec.default.geom.conaffinity, spec.default.geom.density = 0, 0, _GEOM_DENSITY
    spec.default.joint.armature = _ARMATURE
    spec.default.joint.damping[0] = _DAMPING  # [linear, (polynomial terms)]
    body = spec.worldbody.add_body(name=VEHICLE_BODY, pos=xyz, quat=frames.matrix_quat(frames.rpy_matrix(rpy)),
                                   mass=vehicle.mass, ipos=[0.0, 0.0, 0.0], inertia=_hull_inertia(vehicle),
                                   explicitinertial=True)
    # the free joint gets none of the arm joints' armature and damping
    body.add_joint(name=VEHICLE_BODY, type=mujoco.mjtJoint.mjJNT_FREE, armature=0.0, damping=[0.0, 0.0, 0.0])
    body.add_geom(name=HULL_GEOM, type=mujoco.mjtGeom.mjGEOM_BOX, size=np.asarray(vehicle.size, dtype=float) / 2.0,
                  rgba=[0.9, 0.8, 0.2, 0.4])
    body.add_site(name="cob", pos=vehicle.cob).size[0] = 0.02
    for k, t in enumerate(vehicle.thrusters):
        body.add_site(name=thruster_name(k), pos=t.pos).size[0] = 0.03
    if robot is not None:
        add_robot(spec, robot, body, pos=vehicle.mount_xyz, quat=frames.matrix_quat(frames.rpy_matrix(vehicle.mount_rpy)),
                  inertial=True)
    for k, t in enumerate(vehicle.thrusters):
        d = np.asarray(t.direction, dtype=float)
        spec.add_actuator(name=thruster_name(k), target=thruster_name(k), trntype=mujoco.mjtTrn.mjTRN_SITE,
                          gear=[*(d / np.linalg.norm(d)), 0.0, 0.0, 0.0], ctrllimited=mujoco.mjtLimited.mjLIMITED_TRUE,
                          ctrlrange=[-t.max_thrust, t.max_thrust]).set_to_motor()
    if robot is not None and servos:
        for j, lo, hi in zip(robot.joint_names, robot.lower, robot.upper):
            spec.add_actuator(name=servo_name(j), target=j, trntype=mujoco.mjtTrn.mjTRN_JOINT,
                              ctrllimited=mujoco.mjtLimited.mjLIMITED_TRUE,
                              ctrlrange=[float(lo), float(hi)]).set_to_position(kp=SERVO_KP, kv=SERVO_KV)
    return spec


def hover_mjcf(robot: Robot | None, vehicle: VehicleSettings = VehicleSettings(), **kwargs) -> str:
    """:func:`hover_spec` (same arguments) as MJCF text, a file for other tools (MuJoCo writes
    its numbers with 6 significant digits: build models from :func:`hover_spec`)."""
    return hover_spec(robot, vehicle, **kwargs).to_xml()


def hover_model(robot: Robot | None, vehicle: VehicleSettings = VehicleSettings(), **kwargs) -> mujoco.MjModel:
    """The compiled :func:`hover_spec` (same arguments)."""
    return hover_spec(robot, vehicle, **kwargs).compile()


def buoyancy_bodies(model: mujoco.MjModel, robot: Robot | None,
                    vehicle: VehicleSettings) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The bodies that displace water, for :func:`~uvms_jax.hover.buoyancy_xfrc`.

    The hull displaces ``vehicle.volume`` at ``vehicle.cob``. Each arm body displaces the sum of
    its parts' volumes (``robot.inertials``: the arm card's ``buoyancy``) at their
    volume-weighted centre of buoyancy; parts of unknown volume (0) displace nothing. An arm
    body the description gives no mass for is a capsule at the density of water, lifted by its
    own weight at its centre of mass.

    Returns:
      ``(ids (k,), volume (k,) [m³], cob (k, 3) [m, in each body's frame])``.
    """
    ids, volumes, cobs = [model.body(VEHICLE_BODY).id], [vehicle.volume], [np.asarray(vehicle.cob, dtype=float)]
    if robot is not None:
        names = {BASE: base_body(robot), **dict(enumerate(robot.link_names))}
        for body, name in names.items():
            b = model.body(name).id
            parts = [p for p in robot.inertials if p.body == body and p.mass > 0]
            if not parts:  # no mass properties: a capsule of water (hover_spec's geom density)
                volume, cob = model.body_mass[b] / _GEOM_DENSITY, np.array(model.body_ipos[b])
            else:
                volume = sum(p.volume for p in parts)
                if volume <= 0:
                    continue
                cob = sum(p.volume * np.asarray(p.cob, dtype=float) for p in parts) / volume
            ids.append(b)
            volumes.append(volume)
            cobs.append(cob)
    return np.array(ids, dtype=int), np.array(volumes, dtype=float), np.array(cobs, dtype=float).reshape(-1, 3)


def apply_buoyancy(model: mujoco.MjModel, data: mujoco.MjData, bodies: tuple[np.ndarray, np.ndarray, np.ndarray],
                   density: float) -> None:
    """Set ``data.xfrc_applied`` of the buoyant ``bodies`` (:func:`buoyancy_bodies`) to their
    lift (:func:`~uvms_jax.hover.buoyancy_xfrc`) for the pose in ``data`` — whose kinematics
    (``xpos``, ``xmat``, ``xipos``) must be current: call it after ``mj_step1`` or
    ``mj_kinematics``. Other bodies' rows are left as they are.

    Args:
      density: water density [kg/m³] (``VehicleSettings.water_density``; MuJoCo's
        ``opt.density`` is the drag's, which a test may switch off alone).
    """
    ids, volume, cob = bodies
    data.xfrc_applied[ids] = buoyancy_xfrc(data.xpos[ids], data.xmat[ids], data.xipos[ids], volume, cob, density,
                                           model.opt.gravity)


def trimmed(vehicle: VehicleSettings, robot: Robot | None = None, q: Sequence[float] | None = None) -> VehicleSettings:
    """``vehicle`` with the hull's volume and centre of buoyancy (x, y) trimmed so that the
    vehicle carrying ``robot`` at joint angles ``q`` is neutrally buoyant and level.

    Neutral: the hull displaces the water that the whole mass needs less what the arm displaces,
    ``V_h = (m_h + Σ m_b) / ρ − Σ V_b``. Level: with V level, the vertical forces' moments about
    V's origin (the hull's centre of mass) cancel,
    ``ρ V_h c_xy = Σ m_b p_b,xy − ρ Σ V_b c_b,xy`` (p: a body's centre of mass, c: its centre of
    buoyancy, both in V). The height of the centre of buoyancy is kept.

    Args:
      vehicle: the vehicle to trim (its mass, water density, mount and cob height are used).
      robot: the arm, or None (the hull alone: ``V_h = m_h / ρ``, centre of buoyancy over the
        centre of mass).
      q: ``(n_joints,)`` the arm's pose [rad] (default: the middle of its joint ranges).

    Raises:
      ValueError: no water, or an arm that floats the vehicle by itself (``V_h ≤ 0``).
    """
    if not vehicle.water_density > 0:
        raise ValueError("trimmed: water_density must be > 0 to float the vehicle")
    rho = vehicle.water_density
    model = hover_model(robot, dataclasses.replace(vehicle, gravity=0.0))
    data = mujoco.MjData(model)
    if robot is not None:
        q = (robot.lower + robot.upper) / 2.0 if q is None else np.asarray(q, dtype=float)
        if q.shape != (robot.n_joints,):
            raise ValueError(f"q must have {robot.n_joints} joint angles, got shape {q.shape}")
        for j, v in zip(robot.joint_names, q):
            data.qpos[model.jnt_qposadr[model.joint(j).id]] = v
    data.qpos[:3] = 0.0  # V at the world's origin, level
    data.qpos[3:7] = (1.0, 0.0, 0.0, 0.0)
    mujoco.mj_kinematics(model, data)
    ids, volume, cob = buoyancy_bodies(model, robot, vehicle)
    hull = model.body(VEHICLE_BODY).id
    arm = [b for b in range(1, model.nbody) if b != hull]
    arm_mass = float(model.body_mass[arm].sum()) if arm else 0.0
    moment_mass = (model.body_mass[arm, None] * data.xipos[arm]).sum(axis=0) if arm else np.zeros(3)
    is_arm = ids != hull
    cob_world = data.xpos[ids[is_arm]] + np.einsum("kij,kj->ki", data.xmat[ids[is_arm]].reshape(-1, 3, 3), cob[is_arm])
    arm_volume = float(volume[is_arm].sum())
    hull_volume = (vehicle.mass + arm_mass) / rho - arm_volume
    if not hull_volume > 0:
        raise ValueError(f"trimmed: the arm alone floats the vehicle (hull volume {hull_volume:.6g} m³)")
    c_xy = (moment_mass[:2] - rho * (volume[is_arm, None] * cob_world).sum(axis=0)[:2]) / (rho * hull_volume)
    return dataclasses.replace(vehicle, volume=float(hull_volume),
                               cob=(float(c_xy[0]), float(c_xy[1]), float(vehicle.cob[2])))
