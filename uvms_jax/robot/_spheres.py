"""Collision spheres fitted to a robot's collision model: few spheres, each close to its shape.

A compiled collision checker tests spheres, and its time grows with their number; each sphere
must also stay close to the shape it stands for, or the arm looks fatter than it is. Every
shape is fitted on its own (:func:`collision_spheres`): the description's meshes (the vertices
MuJoCo reads, scaled), boxes and cylinders (as MuJoCo collides with them: the convex mesh of
:func:`~uvms_jax.robot.add_robot`), spheres, capsules, the fingers' shapes, and the capsules
along the links of an arm without shapes (:func:`~uvms_jax.robot.link_capsules`).

The fit covers points of the shape's surface (its hull's vertices and samples of its faces at
:data:`SURFACE_STEP`, a capsule's surface samples) with spheres centred inside the shape. A
sphere's outward excess — the farthest any of its points lies outside the shape's convex hull
— is exactly ``max(0, R - depth(c))`` for a centre ``c`` at depth ``depth(c)`` below the hull's
surface (the support function of a convex set, least over directions, is that depth). So each
candidate centre (a grid inside the shape, the axis of a capsule) may take radius
``depth + max_excess``, and a greedy set cover picks the candidate that covers the most points
left, until all are; a point that no candidate covers gets a sphere of radius ``max_excess`` on
itself. A sample counts as covered with a gap to spare (the samples' spacing: the surface
between them is covered too), and each sphere then shrinks to the farthest sample it is the
nearest cover of, plus that gap (never beyond its reach). Results are cached on
disk by the description's digest, the fit's parameters and the shapes.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
import os
from pathlib import Path

import mujoco
import numpy as np
from scipy.spatial import ConvexHull

from uvms_jax.files import write_atomic
from uvms_jax.robot._geometry import Shape
from uvms_jax.robot._mjcf import _hull_vertices, link_capsules
from uvms_jax.robot._model import Robot

__all__ = ["RobotSpheres", "SURFACE_STEP", "collision_spheres", "inscribed_spheres", "shape_vertices", "spheres_cache_dir"]

#: Spacing of the surface samples every sphere set must cover [m]: 4 mm leaves a point between
#: samples at most ~3 mm from one, well inside the spheres' 1 cm excess scale.
SURFACE_STEP = 0.004
#: What every point of a surface lies within of its nearest sample [m] (at most ``SURFACE_STEP / √2``
#: on a capsule's rings, ~0.6 ``SURFACE_STEP`` among a triangle's samples): a sphere counts a
#: sample as covered only with this much to spare, so the surface between samples is covered too.
_GAP = 0.75 * SURFACE_STEP
_CANDIDATES = 4000  # grid candidate centres per shape (about)
_FIT_VERSION = 3  # part of the cache key: changes when the fit does
_BLOCK = 16  # candidate centres per distance block (two blocks of _BLOCK × points floats)


@dataclasses.dataclass(frozen=True, eq=False)
class RobotSpheres:
    """A robot's collision spheres.

    Attributes:
      body: ``(S,)`` int robot body number (-1 base, 0 … n-1).
      finger: ``(S,)`` int index into ``robot.fingers``, -1 for spheres fixed to the body.
      centre: ``(S, 3)`` in the body frame (finger spheres: at finger joint value 0) [m].
      radius: ``(S,)`` [m].
      max_excess: largest outward excess of the spheres over the geometry they stand for [m].
    """

    body: np.ndarray
    finger: np.ndarray
    centre: np.ndarray
    radius: np.ndarray
    max_excess: float

    def __len__(self) -> int:
        return len(self.radius)


def spheres_cache_dir() -> Path:
    """``$XDG_CACHE_HOME/uvms_jax/spheres`` (default ``~/.cache/uvms_jax/spheres``)."""
    root = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(root) / "uvms_jax" / "spheres"


def shape_vertices(shape: Shape) -> np.ndarray:
    """``(k, 3)`` a mesh's vertices as MuJoCo reads them (scaled), or a box's or cylinder's
    convex mesh vertices, in the shape's frame [m]."""
    if shape.kind in ("box", "cylinder"):
        return _hull_vertices(shape)
    if shape.kind != "mesh":
        raise ValueError(f"shape of {shape.link!r}: a {shape.kind} has no vertices")
    if not shape.file:
        return np.asarray(shape.vertices, dtype=float).reshape(-1, 3)
    spec = mujoco.MjSpec()
    spec.add_mesh(name="m", file=shape.file, scale=shape.scale)
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="m")
    model = spec.compile()
    v = model.mesh_vert[model.mesh_vertadr[0]: model.mesh_vertadr[0] + model.mesh_vertnum[0]].astype(float)
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, model.mesh_quat[0])  # MuJoCo re-centres the file's vertices: undo it
    return v @ R.reshape(3, 3).T + model.mesh_pos[0]


def _fibonacci(n: int) -> np.ndarray:
    """``(n, 3)`` unit vectors spread evenly over the sphere."""
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = np.pi * (1.0 + 5 ** 0.5) * k
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def _triangle_samples(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric coordinates ``(u, v)`` of ``n`` points spread evenly over a triangle (a
    2-D Halton sequence folded into it)."""
    k = np.arange(1, n + 1)
    u, v = _radical_inverse(k, 2), _radical_inverse(k, 3)
    fold = u + v > 1
    return np.where(fold, 1 - u, u), np.where(fold, 1 - v, v)


def _radical_inverse(k: np.ndarray, base: int) -> np.ndarray:
    out, f = np.zeros(len(k)), 1.0 / base
    k = k.copy()
    while np.any(k):
        out += f * (k % base)
        k //= base
        f /= base
    return out


def _edge_samples(vertices: np.ndarray, simplices: np.ndarray) -> np.ndarray:
    """Points along every edge of the hull's triangles, at most :data:`SURFACE_STEP` apart."""
    edges = np.unique(np.sort(np.concatenate([simplices[:, [0, 1]], simplices[:, [1, 2]], simplices[:, [0, 2]]]),
                              axis=1), axis=0)
    out = []
    for i, j in edges:
        n = int(np.ceil(np.linalg.norm(vertices[j] - vertices[i]) / SURFACE_STEP))
        out.append(vertices[i] + np.linspace(0, 1, n + 1)[:, None] * (vertices[j] - vertices[i]))
    return np.concatenate(out)


def _polytope(vertices: np.ndarray):
    """Surface samples, depth function and interior candidates of the convex hull of ``vertices``."""
    hull = ConvexHull(vertices)
    A, b = hull.equations[:, :3], hull.equations[:, 3]  # unit outward normals: A x + b <= 0 inside
    points = [vertices[hull.vertices], _edge_samples(vertices, hull.simplices)]
    for tri in vertices[hull.simplices]:
        area = 0.5 * np.linalg.norm(np.cross(tri[1] - tri[0], tri[2] - tri[0]))
        u, v = _triangle_samples(int(np.ceil(area / SURFACE_STEP ** 2)))
        points.append(tri[0] + np.outer(u, tri[1] - tri[0]) + np.outer(v, tri[2] - tri[0]))

    def depth(x: np.ndarray) -> np.ndarray:
        return -np.max(x @ A.T + b, axis=1)

    lo, hi = vertices.min(0), vertices.max(0)
    step = max(float(np.prod(hi - lo) / _CANDIDATES) ** (1 / 3), 1e-4)
    axes = [np.arange(lo[k] + step / 2, hi[k], step) if hi[k] - lo[k] > step else np.array([(lo[k] + hi[k]) / 2])
            for k in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    candidates = np.concatenate([grid[depth(grid) > 0], [vertices[hull.vertices].mean(0)]])
    return np.unique(np.concatenate(points), axis=0), depth, candidates


def _capsule(a: np.ndarray, b: np.ndarray, r: float):
    """Surface samples, depth function and axis candidates of a capsule from ``a`` to ``b``."""
    axis = b - a
    length = float(np.linalg.norm(axis))
    u = axis / length if length > 0 else np.array([0.0, 0.0, 1.0])
    e1 = np.cross(u, [1.0, 0.0, 0.0] if abs(u[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    ring = np.linspace(0, 2 * np.pi, max(8, int(np.ceil(2 * np.pi * r / SURFACE_STEP))), endpoint=False)
    t = np.linspace(0, length, max(2, int(np.ceil(length / SURFACE_STEP)) + 1))
    side = (a + t[:, None, None] * u + r * (np.cos(ring)[None, :, None] * e1 + np.sin(ring)[None, :, None] * e2))
    dirs = _fibonacci(max(16, int(np.ceil(4 * np.pi * r * r / SURFACE_STEP ** 2))))
    caps = np.concatenate([a + r * dirs[dirs @ u <= 0], b + r * dirs[dirs @ u >= 0]])

    def depth(x: np.ndarray) -> np.ndarray:
        s = np.clip((x - a) @ u, 0.0, length)
        return r - np.linalg.norm(x - (a + s[:, None] * u), axis=1)

    candidates = a + np.linspace(0, length, max(2, int(np.ceil(2 * length / SURFACE_STEP)) + 1))[:, None] * u
    return np.concatenate([side.reshape(-1, 3), caps]), depth, candidates


def _solid(shape: Shape):
    """Surface samples, depth function and candidate centres of a shape, in its body's frame;
    None for a sphere (it is its own sphere)."""
    T = shape.T
    if shape.kind == "sphere":
        return None
    if shape.kind == "capsule":
        r, length = shape.size
        a, b = (T @ np.array([0.0, 0.0, s * length / 2, 1.0]) for s in (-1, 1))
        return _capsule(a[:3], b[:3], float(r))
    v = shape_vertices(shape)
    return _polytope(v @ T[:3, :3].T + T[:3, 3])


def _within(centres: np.ndarray, points: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """``(C, P)`` bool: ``points (P, 3)`` within ``radius (C,)`` of ``centres (C, 3)``, the
    distance summed coordinate by coordinate in :func:`numpy.linalg.norm`'s order (the same
    numbers), in blocks of :data:`_BLOCK` centres that stay in the processor's cache."""
    out = np.empty((len(centres), len(points)), bool)
    coords = np.ascontiguousarray(points.T)
    d, term = np.empty((2, min(_BLOCK, len(centres)), len(points)))
    for i in range(0, len(centres), _BLOCK):
        c = centres[i:i + _BLOCK]
        dk, tk = d[:len(c)], term[:len(c)]
        np.square(np.subtract(c[:, :1], coords[0], out=dk), out=dk)
        for k in (1, 2):
            dk += np.square(np.subtract(c[:, k:k + 1], coords[k], out=tk), out=tk)
        np.less_equal(np.sqrt(dk, out=dk), radius[i:i + _BLOCK, None], out=out[i:i + _BLOCK])
    return out


def _cover(points: np.ndarray, depth, candidates: np.ndarray, max_excess: float):
    """Greedy set cover of ``points (P, 3)`` by spheres at ``candidates (C, 3)`` of radius
    ``depth + max_excess``, less the spheres the others make redundant, each shrunk to the
    farthest point it is left with: ``(centres (s, 3), radii (s,), excess)``."""
    covers = _within(candidates, points, depth(candidates) + max_excess - _GAP)
    gain = np.count_nonzero(covers, axis=1)
    left = np.ones(len(points), bool)
    centres, reach = [], []
    while left.any():
        c = int(np.argmax(gain))
        if gain[c] == 0:  # no candidate reaches it: a sphere of the excess on the point itself
            p = points[np.flatnonzero(left)[0]]
            centres.append(p)
            reach.append(np.linalg.norm(points - p, axis=1) <= max_excess - _GAP)
        else:
            centres.append(candidates[c])
            reach.append(covers[c].copy())
        picked = left & reach[-1]
        gain -= np.count_nonzero(covers[:, picked], axis=1)
        left &= ~picked
    reach = np.array(reach)
    keep = np.ones(len(centres), bool)
    count = reach.sum(0)
    for k in np.argsort(reach.sum(1)):  # the least useful first
        if np.all(count[reach[k]] > 1):
            keep[k] = False
            count -= reach[k]
    centres, reach = np.array(centres)[keep], reach[keep]
    d = np.linalg.norm(points[None] - centres[:, None], axis=2)
    owner = np.argmin(np.where(reach, d, np.inf), axis=0)  # the nearest sphere that covers each point
    used = np.isin(np.arange(len(centres)), owner)
    radii = np.array([np.max(d[k, owner == k]) for k in np.flatnonzero(used)])
    centres = centres[used]
    # Shrunk to its samples and what lies between them, never past its reach.
    radii = np.minimum(radii + _GAP, np.maximum(depth(centres), 0.0) + max_excess)
    excess = float(np.max(np.maximum(radii - np.maximum(depth(centres), 0.0), 0.0)))
    return centres, radii, excess


def _fit(shape: Shape, max_excess: float):
    solid = _solid(shape)
    if solid is None:
        return shape.T[None, :3, 3], np.array([float(shape.size[0])]), 0.0
    return _cover(*solid, max_excess)


def _capsule_shapes(robot: Robot) -> list[Shape]:
    """The link capsules of an arm without shapes, as capsule shapes (a sphere where a link has no length)."""
    shapes = []
    for body, end in link_capsules(robot):
        length = float(np.linalg.norm(end))
        if length < 1e-9:
            shapes.append(Shape(body, "sphere", tuple(np.eye(4).ravel()), (robot.link_radius,)))
            continue
        z = end / length
        x = np.cross(z, [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0])
        x /= np.linalg.norm(x)
        T = np.eye(4)
        T[:3, :3] = np.stack([x, np.cross(z, x), z], axis=1)
        T[:3, 3] = end / 2
        shapes.append(Shape(body, "capsule", tuple(T.ravel()), (robot.link_radius, length)))
    return shapes


def _key(robot: Robot, shapes: list[tuple[int, Shape]], max_excess: float) -> str:
    """The cache key: the description's digest, the fit's parameters and the shapes (mesh files
    by path, size and modification time)."""
    def described(s: Shape) -> list:
        stat = Path(s.file).stat() if s.file else None
        return [s.body, s.kind, list(s.pose), list(s.size), s.file, list(s.scale),
                hashlib.sha256(np.asarray(s.vertices, float).tobytes()).hexdigest(),
                None if stat is None else [stat.st_size, stat.st_mtime_ns]]

    text = json.dumps([_FIT_VERSION, robot.digest, repr(float(max_excess)), SURFACE_STEP, _CANDIDATES,
                       [[k, described(s)] for k, s in shapes]])
    return hashlib.sha256(text.encode()).hexdigest()


def _shapes(robot: Robot, shapes) -> list[tuple[int, Shape]]:
    """``(finger index or -1, shape)`` of the robot's collision model and its fingers, or of
    the ``shapes`` given (finger -1)."""
    if shapes is not None:
        return [(-1, s) for s in shapes]
    return ([(-1, s) for s in (robot.shapes or _capsule_shapes(robot))]
            + [(k, s) for k, f in enumerate(robot.fingers) for s in f.shapes])


def collision_spheres(robot: Robot, max_excess: float = 0.01, shapes: tuple[Shape, ...] | None = None) -> RobotSpheres:
    """Spheres covering the robot's collision model (:attr:`Robot.shapes` or the link
    capsules) and its fingers', or the ``shapes`` given (e.g. the card's jaws,
    :func:`~uvms_jax.robot.card_jaws`, or an object in the hand), each reaching at most
    ``max_excess`` [m] beyond the convex hull of the shape it stands for (where a shape allows;
    the excess reached is returned). Cached under :func:`spheres_cache_dir`; a second call
    loads them.

    The card's finger boxes of a robot without fingers (:attr:`Robot.fingers`) are not
    part of its collision model here: they move with the opening and have no finger to hang
    from (fit them as ``shapes`` at an opening).

    Raises:
      ValueError: ``max_excess`` not a finite length above the samples' spacing.
    """
    if not (np.isfinite(max_excess) and max_excess > 2 * _GAP):
        raise ValueError(f"max_excess must be a length above {2 * _GAP} m (the surface samples' spacing), "
                         f"got {max_excess}")
    shapes = _shapes(robot, shapes)
    path = spheres_cache_dir() / f"{_key(robot, shapes, max_excess)}.npz"
    if path.is_file():
        with np.load(path) as z:
            return RobotSpheres(z["body"], z["finger"], z["centre"], z["radius"], float(z["max_excess"]))
    body, finger, centre, radius, excess = [], [], [], [], 0.0
    for k, s in shapes:
        c, r, e = _fit(s, max_excess)
        body += [s.body] * len(r)
        finger += [k] * len(r)
        centre.append(c)
        radius.append(r)
        excess = max(excess, e)
    spheres = RobotSpheres(np.array(body, dtype=int), np.array(finger, dtype=int), np.concatenate(centre),
                           np.concatenate(radius), excess)
    buffer = io.BytesIO()
    np.savez(buffer, body=spheres.body, finger=spheres.finger, centre=spheres.centre, radius=spheres.radius,
             max_excess=excess)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, buffer.getvalue())
    return spheres


_INSCRIBED = 8  # inscribed spheres per shape, at most


def _inscribed(shape: Shape, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Up to ``count`` spheres inside a shape's convex hull (centre ``(k, 3)``, radius ``(k,)``
    [m], in its body's frame): the deepest candidate centre first, then each next the deepest
    one outside the spheres taken so far."""
    solid = _solid(shape)
    if solid is None:
        return shape.T[None, :3, 3], np.array([float(shape.size[0])])
    _, depth, candidates = solid
    d = depth(candidates)
    inside = d > 0
    candidates, d = candidates[inside], d[inside]
    centres, radii = [], []
    while len(centres) < count and len(d):
        k = int(np.argmax(d))
        centres.append(candidates[k])
        radii.append(float(d[k]))
        away = np.linalg.norm(candidates - candidates[k], axis=1) > d[k]
        candidates, d = candidates[away], d[away]
    return np.array(centres).reshape(-1, 3), np.array(radii)


def inscribed_spheres(robot: Robot, per_shape: int = _INSCRIBED, shapes: tuple[Shape, ...] | None = None) -> RobotSpheres:
    """Spheres inside the robot's collision shapes (and its fingers'), or inside the ``shapes``
    given, at most ``per_shape`` each: an obstacle that reaches one of them certainly touches
    the robot (where :func:`collision_spheres` only says it may). ``max_excess`` is 0: they
    reach nowhere outside."""
    if per_shape < 1:
        raise ValueError(f"per_shape must be >= 1, got {per_shape}")
    shapes = _shapes(robot, shapes)
    body, finger, centre, radius = [], [], [], []
    for k, s in shapes:
        c, r = _inscribed(s, per_shape)
        body += [s.body] * len(r)
        finger += [k] * len(r)
        centre.append(c)
        radius.append(r)
    return RobotSpheres(np.array(body, dtype=int), np.array(finger, dtype=int), np.concatenate(centre),
                        np.concatenate(radius), 0.0)
