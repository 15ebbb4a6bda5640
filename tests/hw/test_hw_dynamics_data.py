"""The manufacturer's dynamic data, mapped from its DH link frames into the URDF link frames.

Oracles: the DH forward kinematics written here from the standard DH formula, and the URDF
forward kinematics of the test helpers (numpy, from the URDF table); neither is the code
under test (:func:`uvms_jax.kin.bravo7_inertials`, which maps the table with the library's FK).
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from uvms_jax import bravo7, kin

from _hw_helpers import urdf_link_frames

LOWER = np.array([j.lower for j in bravo7.ARM_JOINTS])
UPPER = np.array([j.upper for j in bravo7.ARM_JOINTS])


def dh_step(d, theta, a, alpha):
    """Standard DH: Rz(θ) Tz(d) Tx(a) Rx(α)."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]])


def dh_fk(q):
    """The manufacturer's table (d, θ, a, α in mm and rad, as published) for URDF angles q:
    DH frames 0…7 in the URDF base frame, and the link frames in which its masses are given
    (frame k-1 turned by θ_{k-1}, before d, a and α)."""
    theta_a = math.atan(5.2 / 293.55)
    rows = [(107.4, math.pi, 46.0, math.pi / 2), (0, -math.pi / 2 + theta_a, 293.6, 0),
            (0, -math.pi / 2 - theta_a, 40.8, -math.pi / 2), (-160.0, 0, 40.8, -math.pi / 2),
            (0, 0, 40.8, -math.pi / 2), (-223.5, 0, 0, math.pi / 2), (0, -math.pi / 2, 120.0, 0)]
    theta = list(-q[:1]) + list(q[1:6]) + [0.0]  # base rotate G turns the other way
    T = np.eye(4)
    T[:3, 3] = (0.0665, 0.0, 0.038)  # on the G axis, 107.4 mm below the F axis
    frames, link_frames = [T], [T]
    for (d, off, a, alpha), th in zip(rows, theta):
        turned = T @ dh_step(0, th + off, 0, 0)
        link_frames.append(turned)
        T = T @ dh_step(d * 1e-3, th + off, a * 1e-3, alpha)
        frames.append(T)
    return frames, link_frames


def body_frames(q):
    """URDF frames of INERTIAL_BODIES (base, G…B, tool)."""
    return [np.eye(4)] + urdf_link_frames(q)


def random_q(rng, n):
    return rng.uniform(LOWER, UPPER, (n, 6))


def test_dh_and_urdf_kinematics_agree_up_to_a_fixed_transform_per_link(rng):
    """DH frame k+1 sits on URDF body k (and the DH end frame on the tool) with a transform
    that is the same in every pose: rotation exactly, translation to within 4 mm (the public
    descriptions differ by a few mm: F→E 293.6 mm in the DH table, 290.6 mm in the URDF)."""
    rel = []
    for q in random_q(rng, 50):
        U, (D, _) = body_frames(q), dh_fk(q)
        rel.append([np.linalg.inv(U[k + 1]) @ D[k + 1] for k in range(6)] + [np.linalg.inv(U[7]) @ D[7]])
    rel = np.array(rel)
    spread = rel - rel.mean(axis=0)
    assert np.max(np.abs(spread[:, :, :3, :3])) < 1e-5  # rad: URDF π is 3.14159
    assert np.max(np.linalg.norm(spread[:, :, :3, 3], axis=-1)) < 4e-3  # m
    # the end frames: positions agree to within the length differences (≤ 15 mm over the arm)
    ends = [np.linalg.norm(body_frames(q)[7][:3, 3] - dh_fk(q)[0][7][:3, 3]) for q in random_q(rng, 20)]
    assert np.ptp(ends) < 8e-3


def test_mapped_inertials_are_the_table_seen_from_the_urdf_frames(rng):
    """In any pose, the table's centres seen from the URDF bodies are the mapped ones to within
    7 mm (the two descriptions' length differences add up along the chain), and the inertia
    tensors are the table's, rotated (the rotation is the same in every pose)."""
    mapped = kin.bravo7_inertials()
    for q in random_q(rng, 20):
        U, (_, L) = body_frames(q), dh_fk(q)
        for k, (src, dst) in enumerate(zip(bravo7.DH_INERTIALS, mapped)):
            to_body = np.linalg.inv(U[k]) @ L[k]
            for a, b in ((src.com, dst.com), (src.cob, dst.cob)):
                np.testing.assert_allclose(to_body[:3, :3] @ a + to_body[:3, 3], b, atol=7e-3)
            I = np.array(src.inertia)
            Idh = np.array([[I[0], I[3], I[4]], [I[3], I[1], I[5]], [I[4], I[5], I[2]]])
            J = np.array(dst.inertia)
            Iurdf = np.array([[J[0], J[3], J[4]], [J[3], J[1], J[5]], [J[4], J[5], J[2]]])
            np.testing.assert_allclose(to_body[:3, :3] @ Idh @ to_body[:3, :3].T, Iurdf, atol=1e-6)  # URDF π: 3e-6 rad
            assert dst.mass == src.mass and dst.volume == src.volume


def test_centres_of_mass_sit_on_their_links(rng):
    """Each mapped centre of mass lies within a link's radius of the segment from its body's
    joint to the next (the jaws: 10 cm beyond the tool frame)."""

    def distance(p, a, b):
        t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0, 1)
        return np.linalg.norm(p - (a + t * (b - a)))

    for q in random_q(rng, 10):
        U = body_frames(q)
        ends = [U[k + 1][:3, 3] for k in range(7)] + [(U[7] @ [0, 0, 0.1, 1])[:3]]
        for k, inertial in enumerate(kin.bravo7_inertials()):
            p = U[k][:3, :3] @ inertial.com + U[k][:3, 3]
            assert distance(p, U[k][:3, 3], ends[k]) < 0.03, (k, bravo7.INERTIAL_BODIES[k])


def test_table_is_physical():
    for inertial in bravo7.DH_INERTIALS:
        xx, yy, zz, xy, xz, yz = inertial.inertia
        w = np.linalg.eigvalsh([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        assert w.min() > 0 and w[0] + w[1] >= w[2] * (1 - 1e-9)  # positive, triangle inequality
    assert sum(i.mass for i in bravo7.DH_INERTIALS) == pytest.approx(9.6)
    # in water (1000 kg/m³) every link is heavier than the water it displaces
    assert all(i.mass > 1000 * i.volume for i in bravo7.DH_INERTIALS)


def test_bravo7_stays_plain_python():
    code = "import sys, uvms_jax.bravo7; print('numpy' in sys.modules or 'jax' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "False"
