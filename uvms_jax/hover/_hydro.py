"""Hydrostatics and the current as pure functions of arrays (NumPy here, ``jax.numpy`` under MJX).

MuJoCo weighs every body but lifts none: its fluid model (``<option density viscosity wind>``)
gives drag only. :func:`buoyancy_xfrc` is the lift of each body, ``ρ V g`` upward at its centre
of buoyancy, as the rows of ``MjData.xfrc_applied`` (a force and a torque at the body's centre
of mass); :func:`current_at` the water's velocity at a time, which becomes ``MjModel.opt.wind``.

Every function takes ``xp`` (``numpy`` or ``jax.numpy``) and uses only operations both have, so
one formula serves the CPU simulator and a batched MJX one.
"""

from __future__ import annotations

import numpy as np

__all__ = ["buoyancy_xfrc", "current_at"]


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
    torque = xp.cross(centre - xipos, force)
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
