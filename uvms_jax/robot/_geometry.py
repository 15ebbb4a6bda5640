"""The collision model of an arm read from its description: its collision primitives and meshes.

URDF ``<collision>`` elements (box, cylinder, sphere, mesh with scale; each at its origin) and
MJCF collision geoms (``contype`` or ``conaffinity`` not 0: box, cylinder, capsule, sphere,
ellipsoid as its bounding box, mesh) are folded into the moving body they are fixed to, as the
inertials are (:mod:`uvms_jax.robot._load`): body ``-1`` the base link, ``i`` the link moved by
joint ``i``, poses at ``q = 0`` in that body's frame (``chain.T_base_joint0[i]``). Fixed links
are folded. The hand: the link the gripper joint moves and those moved by its mimics (URDF
``<mimic>``, MJCF ``<equality><joint>`` with a linear polynomial), each a prismatic/slide joint
hanging from a body of the arm, are the robot's fingers (:class:`~uvms_jax.robot.Finger`), their
shapes (and those of links fixed to them) in the arm body's frame at finger joint value 0; where
the description has none, or the arm is capsules, the :class:`~uvms_jax.robot.Gripper`'s finger
boxes stand for them. Other links moved by joints off the chain are left out.

Mesh files are found relative to the description file, as absolute paths (``file://`` too), or
as ``package://NAME/rest``: the nearest ancestor folder of the description named ``NAME``, then
the entries of ``ROS_PACKAGE_PATH``. MuJoCo reads STL and OBJ files (not COLLADA). When a mesh
does not resolve or MuJoCo cannot read it — or the description has no collision geometry at
all — the whole arm falls back to capsules along the links (the robot's ``link_radius``), and
one log line says why: a partial model would hide links, capsules of a known radius do not.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import os
from collections.abc import Mapping
from pathlib import Path

import mujoco
import numpy as np

from uvms_jax.frames import pose, quat_matrix

__all__ = ["Shape", "SHAPE_KINDS", "SPHERE_SPACING", "capsule_spheres", "description_shapes", "fixed_to", "resolve_mesh"]

log = logging.getLogger(__name__)

#: ``Shape.kind`` values.
SHAPE_KINDS = ("box", "cylinder", "sphere", "capsule", "mesh")
_MESH_SUFFIXES = (".stl", ".obj")  # what MuJoCo reads (and .msh, its own format)
#: Sphere spacing along a capsule and largest grid cell over a mesh of the arm's sphere model [m]:
#: 3 cm keeps a 4 cm capsule's spheres within 2.7 mm of its surface.
SPHERE_SPACING = 0.03


def capsule_spheres(pos, R, radius: float, half_length: float, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Spheres that together contain a capsule (centre ``pos (3,)``, axis ``R[:, 2]``, ``radius``
    and ``half_length`` [m]): at least two centres ``(s, 3)`` along the axis, at most ``spacing``
    [m] apart, each of radius ``sqrt(radius² + (step / 2)²)`` ``(s,)``. The collision checkers'
    one sphere model of a capsule (the planner's compiled checker, docking's JAX test)."""
    n = max(2, int(np.ceil(2 * half_length / spacing)) + 1)
    step = 2 * half_length / (n - 1)
    centres = np.asarray(pos, dtype=float) + np.linspace(-half_length, half_length, n)[:, None] * np.asarray(R)[:, 2]
    return centres, np.full(n, np.hypot(radius, step / 2))


@dataclasses.dataclass(frozen=True)
class Shape:
    """One collision shape of the description, fixed to one body of the robot.

    Attributes:
      body: body number (``-1`` the base link, ``i`` the link moved by joint ``i``).
      kind: ``"box"``, ``"cylinder"``, ``"sphere"``, ``"capsule"`` or ``"mesh"``.
      pose: the shape's frame in the body's frame, 16 numbers of the ``(4, 4)`` matrix row by
        row (:attr:`T`); a cylinder's and a capsule's axis is its z axis, a box's centre and a
        mesh file's origin are its origin.
      size: box: full edges ``(x, y, z)``; cylinder and capsule: ``(radius, length)``, the
        length without the caps; sphere: ``(radius,)``; mesh: ``()`` [m].
      file: mesh: the absolute path of an STL or OBJ file (MuJoCo collides with its convex hull).
      scale: mesh: the file's scale per axis.
      vertices: mesh without a file (an MJCF inline mesh): its vertices, flat ``(3k,)`` [m].
      link: the description's link (URDF) or body (MJCF) it belongs to.
    """

    body: int
    kind: str
    pose: tuple[float, ...]
    size: tuple[float, ...] = ()
    file: str = ""
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    vertices: tuple[float, ...] = ()
    link: str = ""

    def __post_init__(self) -> None:
        if self.kind not in SHAPE_KINDS:
            raise ValueError(f"shape of {self.link!r}: kind {self.kind!r} is not one of {SHAPE_KINDS}")
        if len(self.pose) != 16:
            raise ValueError(f"shape of {self.link!r}: pose needs the 16 numbers of a (4, 4) matrix")
        if self.kind == "mesh" and not (self.file or self.vertices):
            raise ValueError(f"shape of {self.link!r}: a mesh needs a file or vertices")

    @property
    def T(self) -> np.ndarray:
        """``(4, 4)`` the shape's frame in its body's frame."""
        return np.asarray(self.pose, dtype=float).reshape(4, 4)


class _Fallback(Exception):
    """The description's geometry cannot be used: the arm gets capsules (the message says why)."""


def _pose(T: np.ndarray) -> tuple[float, ...]:
    return tuple(float(v) for v in np.asarray(T, dtype=float).reshape(16))


def resolve_mesh(filename: str, folder: Path | None) -> Path | None:
    """The file a description's mesh reference names, or None where it does not resolve.

    Args:
      filename: a path relative to ``folder``, an absolute path, ``file://PATH`` or
        ``package://NAME/rest`` (``NAME`` is looked for among the ancestors of ``folder``, then
        in the entries of ``ROS_PACKAGE_PATH``).
      folder: the description file's folder (None for a description given as text).
    """
    if filename.startswith("file://"):
        filename = filename[len("file://"):]
    if filename.startswith("package://"):
        name, _, rest = filename[len("package://"):].partition("/")
        roots = [] if folder is None else [a for a in (folder, *folder.parents) if a.name == name]
        for entry in filter(None, os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep)):
            entry = Path(entry)
            roots += [entry] if entry.name == name else [entry / name]
        for root in roots:
            if (root / rest).is_file():
                return (root / rest).resolve()
        return None
    path = Path(filename)
    if not path.is_absolute():
        if folder is None:
            return None
        path = folder / path
    return path.resolve() if path.is_file() else None


@functools.lru_cache(maxsize=256)
def _mesh_error(file: str, scale: tuple[float, float, float]) -> str | None:
    """Why MuJoCo cannot use a mesh file in a moving body (None: it can)."""
    if not file.lower().endswith(_MESH_SUFFIXES + (".msh",)):
        return f"MuJoCo reads STL and OBJ meshes, not {Path(file).suffix or 'a file without suffix'} ({file})"
    spec = mujoco.MjSpec()
    spec.add_mesh(name="m", file=file, scale=scale)
    body = spec.worldbody.add_body()
    body.add_joint()
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="m")
    try:
        spec.compile()
    except ValueError as err:
        return f"MuJoCo cannot read mesh {file}: {str(err).strip().splitlines()[0]}"
    return None


def _mesh(file: str, scale, body: int, T: np.ndarray, link: str, folder: Path | None) -> Shape:
    path = resolve_mesh(file, folder)
    if path is None:
        where = "a description given as text" if folder is None else str(folder)
        raise _Fallback(f"mesh {file!r} of link {link!r} does not resolve (from {where})")
    scale = (1.0, 1.0, 1.0) if scale is None else tuple(float(s) for s in np.broadcast_to(np.asarray(scale, float), 3))
    error = _mesh_error(str(path), scale)
    if error is not None:
        raise _Fallback(error)
    return Shape(body, "mesh", _pose(T), file=str(path), scale=scale, link=link)


def fixed_to(name: str, parent_of: Mapping[str, str], bodies: Mapping[str, int],
             moves: Mapping[str, bool] | None = None) -> int | None:
    """The body a link/body is fixed to: itself or its nearest ancestor that is a body; None
    above the base, or (given ``moves``: link → the joint to its parent is not fixed) where a
    joint off the chain moves it. Without ``moves`` such joints are taken at ``q = 0``."""
    while name not in bodies:
        if name not in parent_of or (moves is not None and moves.get(name, False)):
            return None
        name = parent_of[name]
    return bodies[name]


class _NoHand(Exception):
    """The description's fingers cannot be used (the message says why): the finger boxes stand for them."""


def _unit(v) -> tuple[float, float, float]:
    v = np.asarray(v, dtype=float)
    return tuple(float(x) for x in v / np.linalg.norm(v))


def _members(fingers: list[dict], parent_of: Mapping[str, str], moves: Mapping[str, bool],
             names) -> dict[str, int]:
    """Link/body name → finger index, for each finger's link and those fixed below it."""
    own = {f["link"]: k for k, f in enumerate(fingers)}
    members = {}
    for name in names:
        k = fixed_to(name, parent_of, own, moves)
        if k is not None:
            members[name] = k
    return members


def _finger(link: str, joint: str, parent: str, axis, multiplier, offset, parent_of, moves, bodies, frames,
            body_frames) -> dict:
    body = fixed_to(parent, parent_of, bodies, moves)
    if body is None or link not in frames:
        raise _NoHand(f"finger {link!r} does not hang from a body of the arm (its parent is {parent!r})")
    R = (np.linalg.inv(body_frames[body]) @ frames[link])[:3, :3]
    return {"link": link, "joint": joint, "body": body, "axis": _unit(R @ np.asarray(axis, float)),
            "multiplier": float(multiplier), "offset": float(offset)}


def _urdf_fingers(robot, gripper: str | None, parent_of, moves, bodies, frames, body_frames) -> list[dict]:
    """The fingers (:class:`~uvms_jax.robot.Finger` fields, no shapes) of the URDF's gripper joint."""
    if gripper is None:
        return []
    joints = [j for j in robot.joints if j.name == gripper]
    joints += [j for j in robot.joints if j.mimic is not None and j.mimic.joint == gripper]
    fingers = []
    for j in joints:
        if j.type != "prismatic":
            raise _NoHand(f"joint {j.name!r} mimics the gripper joint but is {j.type}, not prismatic")
        mult, off = (1.0, 0.0) if j.mimic is None else (
            1.0 if j.mimic.multiplier is None else j.mimic.multiplier, j.mimic.offset or 0.0)
        axis = (1.0, 0.0, 0.0) if j.axis is None else j.axis
        fingers.append(_finger(j.child, j.name, j.parent, axis, mult, off, parent_of, moves, bodies, frames,
                               body_frames))
    return fingers


def _urdf_shapes(urdf, folder: Path | None, bodies: Mapping[str, int], frames: Mapping[str, np.ndarray],
                 body_frames: Mapping[int, np.ndarray], gripper: str | None = None
                 ) -> tuple[list[Shape], list[dict], list[str]]:
    robot = urdf.robot
    parent_of = {j.child: j.parent for j in robot.joints}
    moves = {j.child: j.type != "fixed" for j in robot.joints}
    try:
        fingers = _urdf_fingers(robot, gripper, parent_of, moves, bodies, frames, body_frames)
    except _NoHand as why:
        log.info("arm %s: the gripper's finger boxes stand for its fingers: %s", robot.name, why)
        fingers = []
    member = _members(fingers, parent_of, moves, [link.name for link in robot.links])
    shapes, off_chain = [], []
    for f in fingers:
        f["shapes"] = []
    for link in robot.links:
        if not link.collisions:
            continue
        k = member.get(link.name)
        body = fixed_to(link.name, parent_of, bodies, moves) if k is None else fingers[k]["body"]
        if body is None or link.name not in frames:
            off_chain.append(link.name)
            continue
        T_body_link = np.linalg.inv(body_frames[body]) @ frames[link.name]
        into = shapes if k is None else fingers[k]["shapes"]
        for c in link.collisions:
            T = T_body_link @ (np.eye(4) if c.origin is None else np.asarray(c.origin, float))
            g = c.geometry
            if g.box is not None:
                into.append(Shape(body, "box", _pose(T), tuple(float(v) for v in g.box.size), link=link.name))
            elif g.cylinder is not None:
                into.append(Shape(body, "cylinder", _pose(T), (float(g.cylinder.radius), float(g.cylinder.length)),
                                  link=link.name))
            elif g.sphere is not None:
                into.append(Shape(body, "sphere", _pose(T), (float(g.sphere.radius),), link=link.name))
            elif g.mesh is not None:
                into.append(_mesh(g.mesh.filename, g.mesh.scale, body, T, link.name, folder))
            else:
                raise _Fallback(f"link {link.name!r} has a collision element without a box, cylinder, sphere or mesh")
    return shapes, fingers, off_chain


def _mat(pos, quat) -> np.ndarray:
    return pose(quat_matrix(quat), pos)


def _mjcf_fingers(model: mujoco.MjModel, names, gripper: str | None, parent_of, moves, bodies, frames,
                  body_frames) -> list[dict]:
    """The fingers (:class:`~uvms_jax.robot.Finger` fields, no shapes) of the MJCF's gripper
    joint: its body and those whose slide joint an ``<equality><joint>`` ties to it linearly
    (``joint1 = polycoef[0] + polycoef[1] · gripper``, references 0)."""
    if gripper is None:
        return []
    jg = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, gripper)
    ties = [(jg, 1.0, 0.0)]
    for e in range(model.neq):
        if model.eq_type[e] == mujoco.mjtEq.mjEQ_JOINT and model.eq_obj2id[e] == jg:
            coef = np.asarray(model.eq_data[e, :5], float)
            if np.any(coef[2:] != 0):
                raise _NoHand(f"equality {e} ties a joint to the gripper joint by a polynomial, not linearly")
            ties.append((int(model.eq_obj1id[e]), coef[1], coef[0]))
    fingers = []
    for j, mult, off in ties:
        b = int(model.jnt_bodyid[j])
        if model.jnt_type[j] != mujoco.mjtJoint.mjJNT_SLIDE or model.body_jntnum[b] != 1:
            raise _NoHand(f"body {names[b]!r} moves with the gripper but not by one slide joint")
        fingers.append(_finger(names[b], model.joint(j).name, parent_of[names[b]], model.jnt_axis[j], mult, off,
                               parent_of, moves, bodies, frames, body_frames))
    return fingers


def _mjcf_shapes(spec: mujoco.MjSpec, model: mujoco.MjModel, folder: Path | None, bodies: Mapping[str, int],
                 frames: Mapping[str, np.ndarray], body_frames: Mapping[int, np.ndarray], gripper: str | None = None
                 ) -> tuple[list[Shape], list[dict], list[str]]:
    names = [model.body(b).name or f"body{b}" for b in range(model.nbody)]
    parent_of = {names[b]: names[int(model.body_parentid[b])] for b in range(1, model.nbody)}
    moves = {names[b]: bool(model.body_jntnum[b]) for b in range(1, model.nbody)}
    try:
        fingers = _mjcf_fingers(model, names, gripper, parent_of, moves, bodies, frames, body_frames)
    except _NoHand as why:
        log.info("arm %s: the gripper's finger boxes stand for its fingers: %s", spec.modelname, why)
        fingers = []
    member = _members(fingers, parent_of, moves, names)
    for f in fingers:
        f["shapes"] = []
    mesh_dir = folder / spec.meshdir if folder is not None and spec.meshdir else folder
    spec_meshes = list(spec.meshes)
    G = mujoco.mjtGeom
    shapes, off_chain = [], []
    for g in range(model.ngeom):
        if not (model.geom_contype[g] or model.geom_conaffinity[g]):
            continue  # a visual geom
        name = names[int(model.geom_bodyid[g])]
        k = member.get(name)
        body = fixed_to(name, parent_of, bodies, moves) if k is None else fingers[k]["body"]
        if body is None or name not in frames:
            off_chain.append(name)
            continue
        into = shapes if k is None else fingers[k]["shapes"]
        T = np.linalg.inv(body_frames[body]) @ frames[name] @ _mat(model.geom_pos[g], model.geom_quat[g])
        t, size = int(model.geom_type[g]), np.asarray(model.geom_size[g], float)
        if t == G.mjGEOM_BOX:
            into.append(Shape(body, "box", _pose(T), tuple(2 * size), link=name))
        elif t == G.mjGEOM_ELLIPSOID:  # its bounding box: never smaller
            into.append(Shape(body, "box", _pose(T), tuple(2 * size), link=name))
        elif t in (G.mjGEOM_CYLINDER, G.mjGEOM_CAPSULE):
            kind = "cylinder" if t == G.mjGEOM_CYLINDER else "capsule"
            into.append(Shape(body, kind, _pose(T), (float(size[0]), 2 * float(size[1])), link=name))
        elif t == G.mjGEOM_SPHERE:
            into.append(Shape(body, "sphere", _pose(T), (float(size[0]),), link=name))
        elif t == G.mjGEOM_MESH:
            m = int(model.geom_dataid[g])
            mesh = spec.mesh(model.mesh(m).name) if model.mesh(m).name else spec_meshes[m]
            if mesh.file:  # the compiled geom pose includes MuJoCo's re-centring of the mesh: undo it
                T_file = T @ np.linalg.inv(_mat(model.mesh_pos[m], model.mesh_quat[m]))
                into.append(_mesh(mesh.file, tuple(mesh.scale), body, T_file, name, mesh_dir))
            else:  # an inline mesh: its compiled vertices in the compiled geom's frame
                a, n = int(model.mesh_vertadr[m]), int(model.mesh_vertnum[m])
                vertices = tuple(map(float, model.mesh_vert[a:a + n].ravel()))
                into.append(Shape(body, "mesh", _pose(T), vertices=vertices, link=name))
        else:  # a plane, height field or SDF: scenery, not a link
            off_chain.append(f"{name} ({G(t).name.removeprefix('mjGEOM_').lower()})")
    return shapes, fingers, off_chain


def description_shapes(name: str, fmt: str, parsed, bodies: Mapping[str, int], frames: Mapping[str, np.ndarray],
                       body_frames: Mapping[int, np.ndarray], link_radius: float, gripper: str | None = None
                       ) -> tuple[tuple[Shape, ...], tuple[dict, ...]]:
    """The description's collision shapes folded into the robot's bodies, or ``()`` (the
    capsules along the links) where it has none or one cannot be used; and its fingers (the
    fields of :class:`~uvms_jax.robot.Finger`, shapes included; ``()`` with capsules). Logs
    which, once.

    Args:
      name: the arm's name (for the log).
      fmt: ``"urdf"`` or ``"mjcf"``.
      parsed: URDF: ``(yourdfpy.URDF, folder)``; MJCF: ``(MjSpec, its compiled MjModel,
        folder)`` — folder: the description file's, or None for a description given as text.
      bodies: description link/body name → body number (the base and the chain's links).
      frames: every link's/body's frame in the base frame at ``q = 0``.
      body_frames: body number → its frame in the base frame at ``q = 0``.
      link_radius: the capsules' radius (for the log).
      gripper: the gripper joint's name in the description (None: no hand to read).
    """
    try:
        if fmt == "urdf":
            shapes, fingers, off_chain = _urdf_shapes(*parsed, bodies, frames, body_frames, gripper)
        else:
            shapes, fingers, off_chain = _mjcf_shapes(*parsed, bodies, frames, body_frames, gripper)
    except _Fallback as why:
        log.warning("arm %s: collision model of capsules along the links (radius %g m): %s", name, link_radius, why)
        return (), ()
    if not shapes:
        log.info("arm %s: the description has no collision geometry on the chain: capsules along the links "
                 "(radius %g m)", name, link_radius)
        return (), ()
    left = (f"; left out (above the base, moved by joints off the chain, or not a link shape): "
            f"{sorted(set(off_chain))}" if off_chain else "")
    hand = (f"; hand: fingers {[f['link'] for f in fingers]} with {sum(len(f['shapes']) for f in fingers)} shapes"
            if fingers else "")
    log.info("arm %s: collision model from the description: %d shapes (%d meshes)%s%s", name, len(shapes),
             sum(s.kind == "mesh" for s in shapes), hand, left)
    return tuple(shapes), tuple({**f, "shapes": tuple(f["shapes"])} for f in fingers)
