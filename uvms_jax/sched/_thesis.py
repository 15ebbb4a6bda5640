"""The thesis's worked example (eq. 4.1) and node layout (Table 5.1), as published.

These are facts from the thesis (docs/theory.md §5), kept in one
place: tests, the experiment's default input and the benchmark all read them from here.
In the extracted text rows 3 and 4 of eq. 4.1 lost their NaN columns; each keeps its single
finite entry, which belongs to the object's only base (cylinder → 7, hexagon → 8).
"""

from __future__ import annotations

import numpy as np

from uvms_jax.sched._problem import PickPlaceProblem

_ = np.nan

#: Table 5.1: node number → name.
THESIS_NODE_NAMES = (
    "start",
    "cube 1",
    "cube 2",
    "cylinder",
    "hexagon",
    "base cube 1",
    "base cube 2",
    "base cylinder",
    "base hexagon",
    "goal",
)

#: docs/theory.md §5: objects go to a base with the same number of vertices.
THESIS_COMPAT = {1: (5, 6), 2: (5, 6), 3: (7,), 4: (8,)}

#: Thesis eq. 4.1 cost matrix (rows: from, columns: to), NaN = move not allowed.
THESIS_EQ41 = np.array(
    [
        [_, 0.4298, 0.1292, 0.6665, 0.3071, _, _, _, _, _],
        [_, _, _, _, _, 0.6248, 0.4110, _, _, _],
        [_, _, _, _, _, 0.4417, 0.5221, _, _, _],
        [_, _, _, _, _, _, _, 0.4070, _, _],
        [_, _, _, _, _, _, _, _, 0.4211, _],
        [0.5186, 0.3987, 0.3710, 0.4603, 0.2716, _, _, _, _, 0.5186],
        [0.3539, 0.3750, 0.3521, 0.3305, 0.0995, _, _, _, _, 0.3539],
        [0.3609, 0.4181, 0.3467, 0.3515, 0.3517, _, _, _, _, 0.3609],
        [0.0031, 0.2099, 0.4139, 0.2742, 0.2520, _, _, _, _, 0.0031],
        [_, _, _, _, _, _, _, _, _, _],
    ]
)
THESIS_EQ41.setflags(write=False)

#: The greedy schedule the thesis reports for eq. 4.1 (section 4.7).
THESIS_EQ41_GREEDY_PATH = (0, 2, 5, 4, 8, 0, 1, 6, 3, 7, 9)


#: Thesis Table 5.5: each solver's time on the eq. 4.1 matrix [ms] (greedy: the thesis's
#: "Dijkstra"; GRASP with its 1000 iterations); the exact solver is ours, with no thesis time.
THESIS_SOLVER_MS = {"greedy": 0.0121, "grasp": 110.228, "astar": 0.9435}


def thesis_problem() -> PickPlaceProblem:
    """The 10-node thesis instance (eq. 4.1 costs, Table 5.1 nodes, start 0, goal 9)."""
    return PickPlaceProblem.from_matrix(THESIS_EQ41, THESIS_COMPAT, start=0, goal=9)
