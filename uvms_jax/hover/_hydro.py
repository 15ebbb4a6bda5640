"""Hydrostatics and the current as pure functions of arrays (NumPy here, ``jax.numpy`` under MJX).

MuJoCo weighs every body but lifts none: its fluid model (``<option density viscosity wind>``)
gives drag only. :func:`buoyancy_xfrc` is the lift of each body, ``ρ V g`` upward at its centre
of buoyancy, as the rows of ``MjData.xfrc_applied`` (a force and a torque at the body's centre
of mass); :func:`current_at` the water's velocity at a time, which becomes ``MjModel.opt.wind``.

Every function takes ``xp`` (``numpy`` or ``jax.numpy``) and uses only operations both have, so
one formula serves the CPU simulator and a batched MJX one.
"""

from __future__ import annotations

import mujoco
import numpy as np

__all__ = ["buoyancy_xfrc", "current_at", "fluid_bodies", "fluid_xfrc"]

_MIN_MASS = 1e-15  # MuJoCo's mjMINVAL: lighter bodies get no fluid force


def _cross(a, b, xp=np):
    """``a × b`` over the last axis (3), written out: NumPy's ``cross`` costs tens of µs of
    overhead on the few rows the simulator passes every physics step."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return xp.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def buoyancy_xfrc(xpos, xmat, xipos, volume, cob, density, gravity, xp=np):
    """Buoyancy of bodies as applied wrenches at their centres of mass.

    Archimedes: the water pushes each body up by the weight of the water it displaces, at the
    centroid of that water (its centre of buoyancy). ``xfrc_applied`` acts at the body's centre
    of mass (``xipos``), so the lift's moment about that point comes with it.

    Args:
      xpos: ``(..., k, 3)`` body frame origins in the world [m] (``MjData.xpos`` rows).
      xmat: ``(..., k, 3, 3)`` or ``(..., k, 9)`` body orientations (``MjData.xmat`` rows).
      xipos: ``(..., k, 3)`` body centres of mass in the world [m] (``MjData.xipos`` rows).
      volume: ``(k,)`` displaced volume of each body [m³].
      cob: ``(k, 3)`` centre of buoyancy of each body in its body frame [m].
      density: water density [kg/m³].
      gravity: ``(3,)`` gravitational acceleration in the world [m/s²] (``MjModel.opt.gravity``).
      xp: the array module (``numpy`` or ``jax.numpy``).

    Returns:
      ``(..., k, 6)``: force [N] then torque about the centre of mass [N·m], world frame.
    """
    R = xp.reshape(xmat, xmat.shape[:-2] + (3, 3) if xmat.shape[-1] == 3 else xmat.shape[:-1] + (3, 3))
    force = -density * volume[:, None] * xp.asarray(gravity)  # (k, 3): against gravity
    centre = xpos + xp.einsum("...kij,kj->...ki", R, cob)  # (..., k, 3) centres of buoyancy
    force = xp.broadcast_to(force, centre.shape)
    torque = _cross(centre - xipos, force, xp)
    return xp.concatenate([force, torque], axis=-1)


def current_at(times, velocities, t, xp=np):
    """The current's velocity at time ``t``: linear between the knots, held beyond them.

    Args:
      times: ``(k,)`` strictly increasing knot times [s] (one knot: a constant current).
      velocities: ``(k, 3)`` the current at the knots, world frame [m/s].
      t: time [s] (a scalar).

    Returns:
      ``(3,)`` water velocity in the world [m/s] (MuJoCo's ``opt.wind``).
    """
    return xp.stack([xp.interp(t, times, velocities[:, i]) for i in range(3)], axis=-1)


# -- the fluid force, as MuJoCo computes it --------------------------------------------------------
def fluid_bodies(model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    """The bodies MuJoCo's inertia-box fluid model acts on, and their equivalent boxes.

    Each body of mass ``m`` and principal inertia ``(I_x, I_y, I_z)`` moves through the fluid as
    the uniform box with the same mass and inertia: edge ``b_x = sqrt(6 (I_y + I_z − I_x) / m)``
    and so on (MuJoCo's ``mj_inertiaBoxFluidModel``).

    Returns:
      ``(ids (k,), box (k, 3) [m])``: bodies of positive mass and their boxes' full edges.
    """
    ids = np.array([b for b in range(1, model.nbody) if model.body_mass[b] > _MIN_MASS], dtype=int)
    inertia, mass = model.body_inertia[ids], model.body_mass[ids]
    signs = np.ones((3, 3)) - 2.0 * np.eye(3)  # row i: −I_i + I_j + I_k
    box = np.sqrt(6.0 * np.maximum(inertia @ signs.T, 1e-12) / mass[:, None])
    return ids, box.reshape(-1, 3)


def fluid_xfrc(xipos, ximat, cvel, root_com, box, density, viscosity, wind, xp=np):
    """MuJoCo's inertia-box drag of bodies in a moving fluid, as ``xfrc_applied`` rows.

    The formula of ``mj_inertiaBoxFluidModel`` (docs/hover.md): in each body's inertia frame,
    with ``(ω, v)`` its angular velocity and the velocity of its centre of mass relative to the
    fluid, the force is ``−3π d β v − ½ ρ (b_y b_z, b_x b_z, b_x b_y) |v| v`` and the torque
    ``−π d³ β ω − ρ (b_x (b_y⁴ + b_z⁴), …) |ω| ω / 64`` (d the boxes' mean edge, β the
    viscosity); both act at the centre of mass.

    Args:
      xipos: ``(..., k, 3)`` the bodies' centres of mass [m] (``MjData.xipos`` rows).
      ximat: ``(..., k, 3, 3)`` or ``(..., k, 9)`` their inertia frames (``MjData.ximat``).
      cvel: ``(..., k, 6)`` their com-based velocities ``(ω, v)`` (``MjData.cvel``: angular,
        then the linear velocity of the point at the root's subtree com), world frame.
      root_com: ``(..., k, 3)`` the centre of mass of each body's root subtree
        (``MjData.subtree_com[body_rootid]``) [m].
      box: ``(k, 3)`` the equivalent boxes' edges [m] (:func:`fluid_bodies`).
      density, viscosity: the fluid's [kg/m³], [Pa·s].
      wind: ``(..., 3)`` the fluid's velocity in the world [m/s] (the current).
      xp: ``numpy`` or ``jax.numpy``.

    Returns:
      ``(..., k, 6)``: force [N] then torque about the centre of mass [N·m], world frame.
    """
    R = xp.reshape(ximat, ximat.shape[:-2] + (3, 3) if ximat.shape[-1] == 3 else ximat.shape[:-1] + (3, 3))
    ang, lin = cvel[..., :3], cvel[..., 3:]
    lin = lin - _cross(xipos - root_com, ang, xp)  # the velocity of the centre of mass
    w_local = xp.einsum("...kji,...kj->...ki", R, ang)
    v_local = xp.einsum("...kji,...kj->...ki", R, lin - xp.asarray(wind)[..., None, :])
    bx, by, bz = box[:, 0], box[:, 1], box[:, 2]
    diam = (bx + by + bz) / 3.0
    area = xp.stack([by * bz, bx * bz, bx * by], axis=-1)
    lever = xp.stack([bx * (by ** 4 + bz ** 4), by * (bx ** 4 + bz ** 4), bz * (bx ** 4 + by ** 4)], axis=-1)
    f_local = -3.0 * np.pi * diam[:, None] * viscosity * v_local - 0.5 * density * area * xp.abs(v_local) * v_local
    t_local = (-np.pi * diam[:, None] ** 3 * viscosity * w_local
               - density * lever * xp.abs(w_local) * w_local / 64.0)
    force = xp.einsum("...kij,...kj->...ki", R, f_local)
    torque = xp.einsum("...kij,...kj->...ki", R, t_local)
    return xp.concatenate([force, torque], axis=-1)
