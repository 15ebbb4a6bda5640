"""The robot model: one arm as data that flows through every stage.

``chain_from_urdf`` and ``chain_from_mjcf`` read the kinematic chain alone (a
:class:`uvms_jax.kin.Chain`) from a description; ``load_robot`` reads a URDF or MJCF
description (the format told by its content) into a
:class:`Robot`: the kinematic chain with its limits, the bodies' mass properties, the
collision shapes of the description (:class:`Shape`; capsules along the links where it has
none or they cannot be read), the gripper and its fingers (:class:`Finger`, where the description
has a hand) and, for a real arm, its hardware profile. ``collision_spheres`` fits few spheres to
that collision model (:class:`RobotSpheres`) for a sphere collision checker. An arm card (YAML: the description file and what no
description format holds) names the rest: ``load_arm("bravo7")`` loads a shipped card
(:func:`shipped_arms`), ``robot_from_config`` a card with overrides or settings alone. ``add_robot`` adds
the one MuJoCo model of the arm, which the planning scene and the simulated arm both use, to a
``mujoco.MjSpec`` (``robot_spec``: the arm alone; ``robot_mjcf``: as a file); ``self_collision_pairs`` finds the link pairs
to leave out of self-collision checks. See docs/robots.md.
"""

from uvms_jax.robot._geometry import SPHERE_SPACING
from uvms_jax.robot._geometry import capsule_spheres
from uvms_jax.robot._load import DESCRIPTIONS
from uvms_jax.robot._load import load_arm
from uvms_jax.robot._load import load_robot
from uvms_jax.robot._load import robot_from_config
from uvms_jax.robot._load import shipped_arms
from uvms_jax.robot._mjcf import TOOL_SITE
from uvms_jax.robot._mjcf import base_body
from uvms_jax.robot._mjcf import card_jaws
from uvms_jax.robot._mjcf import geom_name
from uvms_jax.robot._mjcf import link_capsules
from uvms_jax.robot._mjcf import add_robot
from uvms_jax.robot._mjcf import robot_spec
from uvms_jax.robot._mjcf import robot_mjcf
from uvms_jax.robot._mjcf import self_collision_pairs
from uvms_jax.robot._model import BASE
from uvms_jax.robot._model import BodyInertial
from uvms_jax.robot._model import Finger
from uvms_jax.robot._model import Gripper
from uvms_jax.robot._model import Hardware
from uvms_jax.robot._model import Robot
from uvms_jax.robot._model import Shape
from uvms_jax.robot._parse import CONTINUOUS_LIMITS
from uvms_jax.robot._parse import chain_from_mjcf
from uvms_jax.robot._parse import chain_from_urdf
from uvms_jax.robot._spheres import RobotSpheres
from uvms_jax.robot._spheres import collision_spheres
from uvms_jax.robot._spheres import inscribed_spheres
from uvms_jax.robot._spheres import spheres_cache_dir
