"""Serial chains from robot description files: URDF (parsed by yourdfpy) and MJCF (compiled by MuJoCo).

Both importers reduce the file to the same facts, all at ``q = 0`` and in the chosen base
frame: per moving joint on the path from the base to the tip, its kind, unit axis, a point of
the axis, the frame of the link it moves, limits and speed; then the tool pose. Fixed joints
(URDF) and joint-less bodies (MJCF) are folded into this geometry; joints on branches off the
path (fingers, other arms) are ignored. :func:`uvms_jax.robot.load_robot` reads the rest of a
description (masses, shapes, the gripper) beside the chain.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass

import mujoco
import numpy as np

from uvms_jax import frames
from uvms_jax.kin import PRISMATIC, REVOLUTE, Chain, make_chain, prismatic_twist, revolute_twist

# A continuous joint (URDF) or an unlimited hinge (MJCF) turns forever; the chain gets the limits
# [−π, π], which reach every angle once, so samplers and IK see each pose exactly once.
CONTINUOUS_LIMITS = (-np.pi, np.pi)
DEFAULT_SPEED = 1.0  # [rad/s or m/s] where the file gives no positive velocity limit

# A chain loaded whose Jacobian has full rank (min(6, n)) at none of these many configurations,
# uniform within the limits (fixed seed), is warned about: its dexterity index w is 0 wherever
# it reaches (e.g. every axis parallel). Singular values below RANK_RTOL times the largest are 0.
DEXTERITY_SAMPLES = 64
RANK_RTOL = 1e-9

log = logging.getLogger(__name__)

# MuJoCo's enums as plain ints: the compiled model's arrays hold numpy integers.
_J = mujoco.mjtJoint
_FREE, _BALL, _SLIDE, _HINGE = int(_J.mjJNT_FREE), int(_J.mjJNT_BALL), int(_J.mjJNT_SLIDE), int(_J.mjJNT_HINGE)
_EQ_JOINT = int(mujoco.mjtEq.mjEQ_JOINT)


@dataclass(frozen=True)
class _Joint:
    """One moving joint at q = 0, in the base frame."""

    name: str
    kind: str
    axis: np.ndarray  # (3,) unit
    point: np.ndarray  # (3,) a point of the axis [m]
    frame: np.ndarray  # (4, 4) pose of the link it moves
    lower: float
    upper: float
    speed: float
    link: str = ""  # the link (URDF) or body (MJCF) it moves
    effort: float = 0.0  # [N·m or N]; 0 where the file gives none


def _unit(axis, joint: str) -> np.ndarray:
    axis = np.asarray(axis, dtype=np.float64)
    norm = np.linalg.norm(axis)
    if not np.isfinite(norm) or norm < 1e-12:
        raise ValueError(f"joint {joint!r}: axis {axis} has zero length")
    return axis / norm


def build_chain(joints: list[_Joint], T_base_tool0: np.ndarray, name: str) -> Chain:
    if not joints:
        raise ValueError(f"no moving joint between the base and the tip of {name!r}")
    twists = [
        revolute_twist(j.axis, j.point) if j.kind == REVOLUTE else prismatic_twist(j.axis) for j in joints
    ]
    rank = max_jacobian_rank(np.stack(twists), [j.lower for j in joints], [j.upper for j in joints])
    if rank < min(6, len(joints)):
        log.warning("arm %r: its Jacobian has rank %d at best over %d sampled configurations, below the %d of "
                    "its %d joints (joint axes parallel or coupled?): the tool cannot move in every direction "
                    "its joints promise, and the dexterity index w is 0 at every pose", name, rank,
                    DEXTERITY_SAMPLES, min(6, len(joints)), len(joints))
    return make_chain(
        twists=np.stack(twists),
        T_base_tool0=T_base_tool0,
        lower=[j.lower for j in joints],
        upper=[j.upper for j in joints],
        kinds=[j.kind for j in joints],
        joint_names=[j.name for j in joints],
        T_base_joint0=np.stack([j.frame for j in joints]),
        velocity_limits=[j.speed for j in joints],
        name=name,
    )


def _twist_pose(xi: np.ndarray, theta: float) -> np.ndarray:
    """``exp(ξ̂ θ)`` ``(4, 4)`` of a unit twist ``ξ = [v, ω]`` (``ω`` unit or zero)."""
    v, w = xi[:3], xi[3:]
    T = np.eye(4)
    if np.linalg.norm(w) < 0.5:  # prismatic
        T[:3, 3] = v * theta
        return T
    W = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
    R = np.eye(3) + np.sin(theta) * W + (1 - np.cos(theta)) * W @ W  # Rodrigues
    T[:3, :3], T[:3, 3] = R, (np.eye(3) - R) @ np.cross(w, v) + w * (w @ v) * theta
    return T


def max_jacobian_rank(twists: np.ndarray, lower, upper) -> int:
    """The largest rank of the spatial Jacobian ``(6, n)`` of the chain of unit ``twists``
    ``(n, 6)`` over :data:`DEXTERITY_SAMPLES` configurations uniform within ``lower``,
    ``upper`` ``(n,)`` (a fixed seed); column i is ``Ad(e^{ξ₁q₁} ⋯ e^{ξᵢ₋₁qᵢ₋₁}) ξᵢ``
    (Murray, Li & Sastry, eq. 3.54)."""
    rng = np.random.default_rng(0)
    best = 0
    for q in rng.uniform(np.asarray(lower, float), np.asarray(upper, float), (DEXTERITY_SAMPLES, len(twists))):
        T, columns = np.eye(4), []
        for xi, theta in zip(twists, q):
            R, p = T[:3, :3], T[:3, 3]
            P = np.array([[0.0, -p[2], p[1]], [p[2], 0.0, -p[0]], [-p[1], p[0], 0.0]])
            columns.append(np.concatenate([R @ xi[:3] + P @ R @ xi[3:], R @ xi[3:]]))
            T = T @ _twist_pose(xi, theta)
        sv = np.linalg.svd(np.stack(columns, axis=1), compute_uv=False)
        best = max(best, int(np.sum(sv > RANK_RTOL * sv[0])))
        if best >= min(6, len(twists)):
            break
    return best


def _is_text(source) -> bool:
    return isinstance(source, str) and source.lstrip().startswith("<")


def _pick(what: str, given: str | None, candidates: list[str], known: set[str], hint: str) -> str:
    """The named link/body, or the only candidate; a clear error otherwise."""
    if given is not None:
        if given not in known:
            raise ValueError(f"{what} {given!r} not found; the file has: {', '.join(sorted(known))}")
        return given
    if len(candidates) != 1:
        raise ValueError(f"cannot choose the {what}: candidates are {sorted(candidates)}; pass {hint}")
    return candidates[0]


def _path(parent_of: dict, base: str, tip: str, what: str) -> list[str]:
    """Nodes from just below ``base`` down to ``tip`` (parent_of: child → parent)."""
    path, node = [], tip
    while node != base:
        if node not in parent_of:
            raise ValueError(f"the tip {tip!r} is not below the base {base!r} in this {what}")
        path.append(node)
        node = parent_of[node]
    return path[::-1]


def chain_from_urdf(source, base_link: str | None = None, tip_link: str | None = None, name: str | None = None) -> Chain:
    """The serial chain from ``base_link`` to ``tip_link`` of a URDF.

    Revolute, continuous and prismatic joints become chain joints (in path order); fixed
    joints are folded into the geometry. Origins use URDF's ``rpy`` convention
    (``R = Rz(yaw) Ry(pitch) Rx(roll)``); axes need not be unit vectors. Joint frames are the
    URDF link frames at ``q = 0``; the tool frame is ``tip_link``'s frame (any link is a frame,
    so a named tool frame is just a link). Meshes are never read.

    Args:
      source: a path (``str`` or :class:`~pathlib.Path`) or the URDF text itself.
      base_link: default: the root link.
      tip_link: default: the only leaf link (an error lists the leaves when there are several).
      name: model name; default: the robot's name.

    Returns:
      A :class:`Chain` whose base frame is ``base_link``'s frame. Limits: the URDF's;
      ``[−π, π]`` for continuous joints; speeds from ``<limit velocity>``, 1 where missing or 0.

    Raises:
      ValueError: unknown links, a tip not below the base, and on the path: mimic, floating or
        planar joints, a revolute/prismatic joint without ``<limit>``, or a zero axis.
    """
    urdf = read_urdf(source)
    joints, T_base_tool, _ = urdf_path_joints(urdf, base_link, tip_link)
    return build_chain(joints, T_base_tool, urdf.robot.name if name is None else name)


_FORMATS = {"robot": "URDF", "mujoco": "MJCF"}


def description_bytes(source, what: str) -> tuple[bytes, str]:
    """``(bytes, label)`` of a description given as a path or as its text."""
    if isinstance(source, bytes):
        return source, "<text>"
    if isinstance(source, str) and not source.strip():
        raise ValueError(f"{what} description is an empty string: give a file path or the XML text")
    if _is_text(source):
        return source.encode(), "<text>"
    if not isinstance(source, (str, os.PathLike)):
        raise TypeError(f"{what} description must be a path or the XML text, got {type(source).__name__}")
    path = os.fspath(source)
    if not os.path.isfile(path):
        raise ValueError(f"{what} file not found: {path}")
    with open(path, "rb") as f:
        return f.read(), path


def strict_root(data: bytes, source: str, expected: str | None = None):
    """The root element of a description, parsed strictly (an error names the line and
    column; nothing is recovered); ``expected`` (``"robot"``: URDF, ``"mujoco"``: MJCF) refuses
    the other format by name."""
    from lxml import etree  # yourdfpy's XML library

    try:
        root = etree.fromstring(data, parser=etree.XMLParser(recover=False, resolve_entities=False))
    except etree.XMLSyntaxError as err:
        raise ValueError(f"{source} is not well-formed XML: {' '.join(str(err).split())}") from None  # one line
    if root.getroottree().docinfo.internalDTD is not None:  # entities: what another parser reads differently
        raise ValueError(f"{source} declares a DTD (<!DOCTYPE ... [...]>: entities); a robot description takes none")
    if expected is not None and root.tag != expected:
        found = _FORMATS.get(root.tag)
        raise ValueError(f"{source} is {found + ' (<' + root.tag + '>)' if found else 'a <' + root.tag + '> file'}, "
                         f"not {_FORMATS[expected]} (<{expected}>)")
    return root


def _floats(text: str | None, n: int, where: str, default: str) -> np.ndarray:
    values = (default if text is None else text).split()
    try:
        out = np.array([float(v) for v in values])
    except ValueError:
        raise ValueError(f"{where} {text!r} is not {n} numbers") from None
    if out.shape != (n,):
        raise ValueError(f"{where} {text!r} is not {n} numbers")
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{where} {text!r} is not finite")
    return out


def _check_urdf_tree(root, source: str) -> None:
    """Refuse what a URDF parser would load wrong without a word: unnamed or duplicate links
    and joints, joints between unknown links, a link with two parents or a cycle (a closed
    loop: a URDF is a tree), non-finite or zero axes and origins."""
    links = [e.get("name") for e in root.findall("link")]
    joints = root.findall("joint")
    for kind, names in (("link", links), ("joint", [j.get("name") for j in joints])):
        if any(not n for n in names):
            raise ValueError(f"{source}: a <{kind}> has no name (line {root.find(kind).sourceline})")
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"{source}: {kind} names repeat: {dup}")
    parent_of: dict[str, str] = {}
    for j in joints:
        name = j.get("name")
        ends = {}
        for end in ("parent", "child"):
            e = j.find(end)
            if e is None or not e.get("link"):
                raise ValueError(f"{source}: joint {name!r} has no <{end} link=...> (line {j.sourceline})")
            if e.get("link") not in links:
                raise ValueError(f"{source}: joint {name!r} names an unknown {end} link {e.get('link')!r}")
            ends[end] = e.get("link")
        if ends["child"] in parent_of:
            raise ValueError(f"{source}: link {ends['child']!r} is the child of two joints "
                             f"({parent_of[ends['child']][1]!r} and {name!r}): a closed loop; a URDF is a tree")
        parent_of[ends["child"]] = (ends["parent"], name)
        origin = j.find("origin")
        if origin is not None:
            _floats(origin.get("xyz"), 3, f"joint {name!r}: origin xyz", "0 0 0")
            _floats(origin.get("rpy"), 3, f"joint {name!r}: origin rpy", "0 0 0")
        if j.get("type") in ("revolute", "continuous", "prismatic", "planar"):
            axis = j.find("axis")
            xyz = _floats(None if axis is None else axis.get("xyz"), 3, f"joint {name!r}: axis", "1 0 0")
            if np.linalg.norm(xyz) < 1e-12:
                raise ValueError(f"joint {name!r}: axis {xyz} has zero length")
    for link in parent_of:  # a cycle has no root above it
        seen, node = {link}, link
        while node in parent_of:
            node = parent_of[node][0]
            if node in seen:
                raise ValueError(f"{source}: the joints above link {link!r} form a cycle: a closed loop; a URDF is a tree")
            seen.add(node)


def read_urdf(source):
    """A parsed URDF (``yourdfpy.URDF``, meshes not loaded) from a path or the URDF text,
    read strictly: malformed XML, an MJCF file, a closed loop, repeated names and bad numbers
    are errors that say where (:func:`strict_root`), never a lenient second try."""
    import yourdfpy  # the URDF parser; imported here, as only robot files need it

    from lxml import etree

    data, label = description_bytes(source, "URDF")
    root = strict_root(data, label, "robot")
    _check_urdf_tree(root, label)
    # yourdfpy builds its model from this strictly parsed tree: its own loader (URDF.load)
    # parses again and, where its parse fails, retries in recovery mode; that path is never taken.
    etree.strip_tags(root, etree.Comment)
    return yourdfpy.URDF(robot=yourdfpy.URDF._parse_robot(xml_element=root), build_scene_graph=False,
                         load_meshes=False, load_collision_meshes=False,
                         mesh_dir=os.path.dirname(label) if label != "<text>" else "")


def urdf_path_joints(urdf, base_link: str | None, tip_link: str | None) -> tuple[list[_Joint], np.ndarray, str]:
    """The moving joints from ``base_link`` to ``tip_link`` of a parsed URDF (see
    :func:`chain_from_urdf`), the tip's pose in the base frame at ``q = 0`` ``(4, 4)``, and the base
    link's name."""
    robot = urdf.robot
    links = {link.name for link in robot.links}
    joint_of = {j.child: j for j in robot.joints}
    parents = {j.parent for j in robot.joints}
    base = _pick("base link", base_link, sorted(links - set(joint_of)), links, "base_link=")
    tip = _pick("tip link", tip_link, sorted(links - parents), links, "tip_link=")
    T = np.eye(4)
    joints = []
    for link in _path({c: j.parent for c, j in joint_of.items()}, base, tip, "URDF"):
        j = joint_of[link]
        if j.mimic is not None:
            raise ValueError(f"joint {j.name!r} mimics {j.mimic.joint!r}: coupled joints are not supported in a chain")
        if j.type in ("floating", "planar"):
            raise ValueError(f"joint {j.name!r} is {j.type}: only revolute, continuous, prismatic and fixed joints")
        if j.type not in ("fixed", "revolute", "continuous", "prismatic"):
            raise ValueError(f"joint {j.name!r} has unknown type {j.type!r}")
        T = T @ (np.eye(4) if j.origin is None else np.asarray(j.origin, dtype=np.float64))
        if j.type == "fixed":
            continue
        joints.append(urdf_joint(j, T, link))
    return joints, T, base


def urdf_joint(j, T: np.ndarray, link: str) -> _Joint:
    """A moving URDF joint whose child ``link`` has the pose ``T (4, 4)`` at ``q = 0``."""
    if j.type == "continuous":
        lower, upper = CONTINUOUS_LIMITS
    elif j.limit is None or j.limit.lower is None or j.limit.upper is None:
        raise ValueError(f"{j.type} joint {j.name!r} needs <limit lower=… upper=…>")
    else:
        lower, upper = float(j.limit.lower), float(j.limit.upper)
        if not lower < upper:
            raise ValueError(f"joint {j.name!r}: limits [{lower}, {upper}] are inverted or empty")
    speed = j.limit.velocity if j.limit is not None and j.limit.velocity else None
    effort = j.limit.effort if j.limit is not None and j.limit.effort else 0.0
    return _Joint(
        name=j.name,
        kind=PRISMATIC if j.type == "prismatic" else REVOLUTE,
        axis=T[:3, :3] @ _unit(j.axis, j.name),
        point=T[:3, 3].copy(),
        frame=T.copy(),
        lower=lower,
        upper=upper,
        speed=float(speed) if speed and speed > 0 else DEFAULT_SPEED,
        link=link,
        effort=float(effort),
    )


def chain_from_mjcf(
    source,
    base_body: str | None = None,
    tip_body: str | None = None,
    tip_site: str | None = None,
    name: str | None = None,
) -> Chain:
    """The serial chain from ``base_body`` to a tip body or site of an MJCF model.

    The model is compiled by MuJoCo (:class:`mujoco.MjSpec`), then posed at ``qpos = 0`` of
    every hinge and slide joint; the chain's joint values are MuJoCo's ``qpos`` (a joint's
    ``ref`` is honoured). Hinges become revolute joints, slides prismatic; several joints in
    one body follow in the file's order. Joint frames are the moved body's frame at ``q = 0``
    with its origin on the joint axis. MuJoCo has no speed limits: every speed is 1.

    Args:
      source: a path (``str`` or :class:`~pathlib.Path`; meshes resolve relative to it) or
        the MJCF text.
      base_body: default: the world frame.
      tip_body, tip_site: the tool frame (give at most one); default: the only leaf body.
      name: model name; default: the MJCF model's name.

    Returns:
      A :class:`Chain` whose base frame is ``base_body``'s frame. Limits: the joint ranges;
      ``[−π, π]`` for unlimited hinges.

    Raises:
      ValueError: unknown names, a tip not below the base, and on the path: ball or free
        joints, an unlimited slide, or a joint coupled to another by an equality constraint.
    """
    joints, T_base_tool, model_name = mjcf_path_joints(source, base_body, tip_body, tip_site)
    return build_chain(joints, T_base_tool, model_name if name is None else name)


def mjcf_path_joints(source, base_body: str | None, tip_body: str | None,
                     tip_site: str | None) -> tuple[list[_Joint], np.ndarray, str]:
    """The moving joints from the base body to the tip of an MJCF model (see
    :func:`chain_from_mjcf`), the tip's pose in the base frame at ``q = 0`` ``(4, 4)``, and the
    model's name."""
    if tip_body is not None and tip_site is not None:
        raise ValueError("give tip_body or tip_site, not both")
    data, label = description_bytes(source, "MJCF")
    strict_root(data, label, "mujoco")  # MuJoCo would read a URDF too, as another model
    spec = mujoco.MjSpec.from_string(data.decode()) if label == "<text>" else mujoco.MjSpec.from_file(label)
    model = spec.compile()
    data = mujoco.MjData(model)
    data.qpos[:] = model.qpos0
    hinge_or_slide = np.isin(model.jnt_type, (_HINGE, _SLIDE))
    data.qpos[model.jnt_qposadr[hinge_or_slide]] = 0.0
    mujoco.mj_kinematics(model, data)

    bodies = {model.body(b).name or f"body{b}": b for b in range(model.nbody)}
    body_name = {b: n for n, b in bodies.items()}
    parent_of = {body_name[b]: body_name[int(model.body_parentid[b])] for b in range(1, model.nbody)}
    base = _pick("base body", base_body, [body_name[0]], set(bodies), "base_body=")
    if tip_site is not None:
        sites = {model.site(s).name for s in range(model.nsite)}
        if tip_site not in sites:
            raise ValueError(f"site {tip_site!r} not found; the model has: {', '.join(sorted(sites))}")
        sid = model.site(tip_site).id
        tip = body_name[int(model.site_bodyid[sid])]
        T_world_tool = frames.pose(np.reshape(data.site_xmat[sid], (3, 3)), data.site_xpos[sid])
    else:
        leaves = sorted(set(parent_of) - set(parent_of.values()))
        tip = _pick("tip body", tip_body, leaves, set(bodies), "tip_body= or tip_site=")
        T_world_tool = frames.pose(np.reshape(data.xmat[bodies[tip]], (3, 3)), data.xpos[bodies[tip]])
    T_base_world = np.linalg.inv(frames.pose(np.reshape(data.xmat[bodies[base]], (3, 3)), data.xpos[bodies[base]]))

    coupled = {
        int(j)
        for e in range(model.neq)
        if int(model.eq_type[e]) == _EQ_JOINT
        for j in (model.eq_obj1id[e], model.eq_obj2id[e])
        if j >= 0
    }
    joints = []
    for body in _path(parent_of, base, tip, "MJCF model"):
        b = bodies[body]
        for j in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b]):
            jname = model.joint(j).name or f"joint{j}"
            jtype = int(model.jnt_type[j])
            if jtype in (_FREE, _BALL):
                kind = "free" if jtype == _FREE else "ball"
                raise ValueError(f"joint {jname!r} is a {kind} joint: only hinge and slide joints form a chain")
            if j in coupled:
                raise ValueError(f"joint {jname!r} is coupled to another by an equality constraint")
            revolute = jtype == _HINGE
            if model.jnt_limited[j]:
                lower, upper = (float(x) for x in model.jnt_range[j])
            elif revolute:
                lower, upper = CONTINUOUS_LIMITS
            else:
                raise ValueError(f"slide joint {jname!r} has no range: give it limited=\"true\" range=\"…\"")
            frame = T_base_world @ frames.pose(np.reshape(data.xmat[b], (3, 3)), data.xanchor[j])
            joints.append(
                _Joint(
                    name=jname,
                    kind=REVOLUTE if revolute else PRISMATIC,
                    axis=_unit(T_base_world[:3, :3] @ data.xaxis[j], jname),
                    point=frame[:3, 3].copy(),
                    frame=frame,
                    lower=lower,
                    upper=upper,
                    speed=DEFAULT_SPEED,
                    link=body,
                    effort=float(model.jnt_actfrcrange[j, 1]) if model.jnt_actfrclimited[j] else 0.0,
                )
            )
    return joints, T_base_world @ T_world_tool, spec.modelname or "mjcf"
