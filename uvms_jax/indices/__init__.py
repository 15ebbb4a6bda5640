"""Dexterity indices (docs/theory.md §2): manipulability w, KCI (for any number of joints and a
chosen task space), normalised Jacobian, area manipulability M_a (docking paper eq. 1) and
static joint torques."""

from uvms_jax.indices._area import approach_down
from uvms_jax.indices._area import area_manipulability
from uvms_jax.indices._area import control_points
from uvms_jax.indices._area import max_branch_manipulability
from uvms_jax.indices._area import tool_targets
from uvms_jax.indices._indices import joint_torques
from uvms_jax.indices._indices import kci
from uvms_jax.indices._indices import kci_from_rows
from uvms_jax.indices._indices import kci_of
from uvms_jax.indices._indices import manipulability
from uvms_jax.indices._indices import manipulability_from_rows
from uvms_jax.indices._indices import manipulability_of
from uvms_jax.indices._indices import normalized_jacobian
from uvms_jax.indices._indices import payload_wrench
from uvms_jax.indices._indices import singular_values
from uvms_jax.indices._indices import task_rows
from uvms_jax.indices._singular import near_singular_poses
