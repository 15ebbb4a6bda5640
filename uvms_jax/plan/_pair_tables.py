"""Distance tables of the robot's self pairs two joints apart.

The relative pose of two groups on bodies ``b`` and ``b + 2`` depends on two joints only
(``b + 1`` and ``b + 2``). Their least distance, measured by MuJoCo on the exact geometry over a
grid of those two joints, settles such a pair in one lookup wherever the state is further than
the table's bound from contact. The bound is rigorous: turning joint ``b + 1`` by ``δ`` moves a
point of the outer group by at most ``r₁|δ|`` (``r₁`` its largest distance from that joint's
axis), joint ``b + 2`` by at most ``r₂|δ|``, so half a spacing ``h`` on each changes the pair's
distance by at most ``(r₁ + r₂) h / 2``. Closer to contact than that, the spheres (and MuJoCo)
decide as for any pair.

On the Panda the pair of link 5 and the hand (link 7's group) is the costliest self pair for
the spheres: its covering spheres' excess overlaps over a wide band of wrist angles, where a
table answers in one lookup. Tables are cached on disk by the geometry's content.
"""

from __future__ import annotations

import hashlib
import io
import json

import mujoco
import numpy as np

from uvms_jax.files import write_atomic
from uvms_jax.plan._vector_kernels import distance_table, without_tables
from uvms_jax.robot import spheres_cache_dir

__all__ = ["TABLE_BOUND", "pair_tables"]

#: The largest change of a tabled pair's distance between a state and its nearest grid node
#: [m]: it sets the grid's spacing. 3 mm keeps a Panda wrist table near 10⁵ nodes (a second to
#: build once) while the band it leaves to the spheres stays narrow.
TABLE_BOUND = 0.003
_TOLERANCE = 1e-5  # [m] MuJoCo's convex distance tolerance and float32 storage, added to the bound
_VERSION = 1  # part of the cache key: changes when the tables do
_LOADED: dict = {}  # the tables read or built in this process, by cache path (read-only)


def _outer_reach(side, g: int) -> float:
    """The largest distance [m] of group ``g``'s geometry from its body's origin (its covering
    spheres contain the geometry's hull)."""
    lo, hi = int(side.groups[g, 0]), int(side.groups[g, 1])
    s = side.spheres[lo:hi]
    return float(np.max(np.linalg.norm(s[:, :3], axis=1) + s[:, 3]))


def _geometry_digest(exact, side, g1: int, g2: int, grid: list) -> str:
    """The cache key: the two groups' geoms (kind, size, pose in their body, mesh vertices), the
    chain's joint rows and the grid."""
    m, ranges, geoms = exact.model, *exact.arrays(np.zeros(0, bool))[4:6]
    parts = [_VERSION, grid, hashlib.sha256(side.kin.tobytes()).hexdigest()]
    for g in (g1, g2):
        for k in geoms[ranges[g, 0]:ranges[g, 1]]:
            mesh = int(m.geom_dataid[k])
            verts = m.mesh_vert[m.mesh_vertadr[mesh]:m.mesh_vertadr[mesh] + m.mesh_vertnum[mesh]] if (
                m.geom_type[k] == mujoco.mjtGeom.mjGEOM_MESH and mesh >= 0) else np.zeros(0)
            parts.append([g, int(m.geom_type[k]), m.geom_size[k].tolist(), m.geom_pos[k].tolist(),
                          m.geom_quat[k].tolist(), hashlib.sha256(np.ascontiguousarray(verts).tobytes()).hexdigest()])
    return hashlib.sha256(json.dumps(parts).encode()).hexdigest()


def _table(exact, side, g1: int, g2: int) -> tuple[np.ndarray, np.ndarray] | None:
    """``(meta (8,), values (Na, Nb))`` of the pair ``g1, g2`` (see
    :mod:`uvms_jax.plan._vector_kernels`), or None where it is not two revolute joints apart
    or holds a shape attached for the query (not part of the robot's description)."""
    robot, groups = side.robot, side.groups
    parts = [side.group_bodies[g][1] for g in (g1, g2)]
    if any(p >= len(robot.fingers) for p in parts):
        return None
    b1, b2 = int(groups[g1, 2]), int(groups[g2, 2])
    if abs(b2 - b1) != 2:
        return None
    ja, jb = min(b1, b2) + 1, min(b1, b2) + 2
    if side.kin[ja, 15] != 0.0 or side.kin[jb, 15] != 0.0:
        return None
    reach = _outer_reach(side, g1 if b1 > b2 else g2)
    r1 = float(np.linalg.norm(side.kin[jb, 9:12])) + reach  # from joint ja's axis, through jb's origin
    spacing = 2 * TABLE_BOUND / (r1 + reach)
    lower, upper = robot.lower, robot.upper
    na, nb = (int(np.ceil((upper[j] - lower[j]) / spacing)) + 1 for j in (ja, jb))
    grid = [ja, jb, float(lower[ja]), float(lower[jb]), spacing, na, nb]
    meta = np.array([ja, jb, lower[ja], lower[jb], spacing, TABLE_BOUND + _TOLERANCE, na, nb], dtype=np.float64)
    path = spheres_cache_dir() / f"table-{_geometry_digest(exact, side, g1, g2, grid)}.npy"
    if path in _LOADED:  # a checker per world reuses the robot's tables: read from disk once
        return meta, _LOADED[path]
    if path.is_file():
        _LOADED[path] = np.load(path)
        _LOADED[path].setflags(write=False)
        return meta, _LOADED[path]
    values = distance_table(exact.arrays(np.zeros(0, bool)), g1, g2, ja, jb, float(lower[ja]), float(lower[jb]),
                            spacing, na, nb, robot.n_joints)
    buffer = io.BytesIO()
    np.save(buffer, values)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, buffer.getvalue())
    values.setflags(write=False)
    _LOADED[path] = values
    return meta, values


def pair_tables(exact, side, pairs: np.ndarray) -> tuple:
    """The model's ``tables`` entry for the checked ``pairs (P, 2)`` of ``side`` (a
    :class:`~uvms_jax.plan.RobotSpheresModel`), measured on ``exact`` (its
    :class:`~uvms_jax.plan.ExactChecker`): a table for each pair two revolute joints apart."""
    index, metas, values = np.full(len(pairs), -1, np.int64), [], []
    for p, (g1, g2) in enumerate(pairs):
        found = _table(exact, side, int(g1), int(g2))
        if found is not None:
            index[p] = len(metas)
            metas.append(found[0])
            values.append(found[1])
    if not metas:
        return without_tables(len(pairs))
    shape = np.max([v.shape for v in values], axis=0)
    stacked = np.full((len(values), *shape), np.nan, np.float32)  # never read: lookups stay in their table
    for k, v in enumerate(values):
        stacked[k, :v.shape[0], :v.shape[1]] = v
    return index, np.stack(metas), stacked
