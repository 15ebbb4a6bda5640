"""What the three papers print, transcribed once: the analysis and the tests read it from here.

[D11] Sotiropoulos, Aspragathos & Andritsos 2011 (docking), [D16] Sotiropoulos & Aspragathos
2016 (surrogates of dexterity indices), [T22] the pick-and-place thesis of 2022; section and
equation numbers refer to docs/theory.md. Plain NumPy and tuples. The stages keep their own
defaults as literals; tests/papers checks those equal to the tables here.
"""

from __future__ import annotations

import numpy as np

# ----------------------------------------------------------------------------------------------
# Docking paper [D11] (theory §3); lengths [m], angles [rad], G at the centre of the top face.
# ----------------------------------------------------------------------------------------------

#: [D11] §IV: arm link lengths ``(l0, l1, l2)`` [m] (theory §1.1).
D11_ARM_LENGTHS = (0.1, 0.4, 0.4)
#: [D11] §IV: edge of the square task area K, L, M, N on the top face [m].
D11_TASK_SIZE = 0.4
#: [D11] §IV: the block under the task, ``(x, y, z)`` [m].
D11_BLOCK_SIZE = (2.0, 2.0, 2.0)
#: [D11] §IV: initial manipulator base position in G [m] (eq. 3).
D11_P_INIT = (-2.0, -2.0, 2.0)
#: [D11] §IV: vehicle base point (suction cup) in B [m] (eq. 5).
D11_P_BP = (-0.3, 0.0, -0.2)
#: [D11] Table 3: seven GA runs, ``(7, 6)``: x, y, z [m], ψ [rad], fitness, M_a.
D11_TABLE3 = np.array([
    [-0.32, -0.36, 0.24, 0.79, 2.95, 0.181],
    [-0.49, -0.32, 0.23, 0.83, 2.34, 0.137],
    [-0.28, -0.46, 0.24, 0.77, 2.55, 0.151],
    [-0.36, -0.38, 0.22, 0.74, 2.26, 0.134],
    [-0.36, -0.37, 0.24, 0.78, 2.38, 0.141],
    [-0.31, -0.39, 0.20, 0.79, 2.64, 0.164],
    [-0.31, -0.38, 0.21, 0.73, 2.84, 0.177],
])
D11_TABLE3.flags.writeable = False
#: [D11] Table 4: arm configurations ``(6,)`` [rad] at the control points K, L, M, N for run 1.
D11_TABLE4 = {
    "K": (2.724, 2.241, 2.185, -1.7e-15, -2.567, 2.467),
    "L": (0.657, 0.137, -1.348, 0.0, 0.359, 1.695),
    "M": (0.098, -0.608, 0.377, 9.45e-17, 1.802, 0.888),
    "N": (-0.340, -1.279, 1.438, -6.6e-17, 1.412, -0.391),
}
#: [D11] §IV, Fig. 10: the ill-placed pose ``(x, y, z [m], ψ [rad])``.
D11_ILL_PLACED_POSE = (-0.491, -0.464, 0.213, 0.83)

# ----------------------------------------------------------------------------------------------
# Dexterity paper [D16] (theory §4)
# ----------------------------------------------------------------------------------------------

#: [D16] Table 3: design parameters per network (E, E_mse, E_th, L_iter, L_epochs, L_s, T);
#: None where the parameter does not apply to the network.
D16_TABLE3 = {
    "rbfn_w": (0.02, 1e-6, 1e-2, None, None, 10, 1000),
    "rbfn_kci": (0.02, 1e-6, 1e-4, None, None, 10, 1000),
    "ffbn_w": (0.02, 1e-3, None, 100, 100, None, 1000),
    "ffbn_kci": (0.02, 5e-6, None, 100, 100, None, 1000),
}
#: [D16] Table 4 (operations per evaluation) and Table 5 (seconds for 1000 inputs, Matlab on an
#: i7-3930K) per network and for the analytic indices, with the networks' hidden units.
D16_NETWORKS = {
    "ffbn_w": {"hidden_units": 8, "operation_count": 184, "seconds_1000": 0.0057},
    "ffbn_kci": {"hidden_units": 25, "operation_count": 775, "seconds_1000": 0.0057},
    "rbfn_w": {"hidden_units": 149, "operation_count": 4172, "seconds_1000": 0.0152},
    # RBFN-KCI units: 142, from its operation count (28 per unit, as RBFN-w's 4172 over 149 units).
    "rbfn_kci": {"hidden_units": 142, "spread": 8.9, "operation_count": 3976, "seconds_1000": 0.0152},
    "analytic_w": {"operation_count": 21810, "seconds_1000": 0.7043},
    "analytic_kci": {"operation_count": 21594, "seconds_1000": 0.7283},
}

# ----------------------------------------------------------------------------------------------
# Thesis [T22] (theory §5)
# ----------------------------------------------------------------------------------------------

# Weights K of the thesis's scenarios, in the metric order below.
_EQUAL = (0.2,) * 5
_SPEED = (0.1, 0.35, 0.35, 0.1, 0.1)
_SECURITY = (0.1, 0.1, 0.1, 0.6, 0.1)
_SECURITY_TORQUE = (0.1, 0.1, 0.1, 0.35, 0.35)
_PLANNING_TIME = (0.6, 0.1, 0.1, 0.1, 0.1)

#: [T22] Tables 5.2–5.9, A.1–A.5: per algorithm ``(name, path, K (5,), N (5,), C, time [ms] or
#: None)``. Metric order: planning time, joint movement, EE distance, security, max torque.
T22_TABLES = {
    "5.2": [("Dijkstra", "0-4-8-0-3-7-0-1-5-0-2-6-9", _EQUAL, (3.647, 1.504, 3.574, 4.603, 5.779), 3.821, None),
            ("GRASP", "0-4-8-3-7-1-6-2-5-9", _EQUAL, (1.991, 1.75, 3.094, 2.875, 5.298), 3.001, None),
            ("A*", "0-4-8-3-7-2-6-1-5-9", _EQUAL, (3.001, 1.2, 2.598, 2.791, 5.28), 2.974, None)],
    "5.3": [("Dijkstra", "0-4-8-0-3-7-0-1-5-0-2-6-9", _EQUAL, (2.007, 1.498, 3.577, 4.601, 5.806), 3.498, None),
            ("GRASP", "0-4-8-1-5-0-3-7-2-6-9", _EQUAL, (2.01, 1.557, 3.283, 3.17, 4.82), 2.968, None),
            ("A*", "0-4-8-3-7-2-6-1-5-9", _EQUAL, (1.948, 1.2, 2.597, 2.789, 5.281), 2.763, None)],
    "5.4": [("Dijkstra", "0-4-8-0-3-7-0-1-5-0-2-6-9", _EQUAL, (3.036, 1.512, 3.666, 4.6, 5.925), 3.748, None),
            ("GRASP", "0-4-8-1-6-3-7-0-2-5-9", _EQUAL, (1.686, 1.588, 3.039, 3.503, 5.739), 3.111, None),
            ("A*", "0-4-8-3-7-2-6-1-5-9", _EQUAL, (2.674, 1.201, 2.597, 2.788, 5.28), 2.908, None)],
    "5.5": [("Dijkstra", "0-4-8-0-3-7-0-1-5-0-2-6-9", _EQUAL, (3.647, 1.504, 3.574, 4.603, 5.779), 3.821, 0.0121),
            ("GRASP", "0-4-8-3-7-1-6-2-5-9", _EQUAL, (1.991, 1.75, 3.094, 2.875, 5.298), 3.001, 110.228),
            ("A*", "0-4-8-3-7-2-6-1-5-9", _EQUAL, (3.001, 1.2, 2.598, 2.791, 5.28), 2.974, 0.9435)],
    "5.6": [("Dijkstra", "0-4-8-0-3-7-0-2-5-0-1-6-9", _SPEED, (2.594, 2.041, 3.966, 4.602, 5.741), 3.396, 0.0222),
            ("GRASP", "0-4-8-3-7-2-6-1-5-9", _SPEED, (3.001, 1.2, 2.598, 2.791, 5.28), 2.437, 119.336),
            ("A*", "0-4-8-3-7-0-2-6-1-5-9", _SPEED, (3.149, 1.049, 2.659, 3.502, 5.777), 2.541, 1.0443)],
    "5.7": [("Dijkstra", "0-3-7-1-5-4-8-2-6-9", _SECURITY, (4.122, 1.652, 3.678, 2.344, 5.335), 2.885, 0.0164),
            ("GRASP", "0-4-8-2-5-3-7-1-6-9", _SECURITY, (2.981, 2.127, 3.823, 2.321, 5.251), 2.811, 92.5959),
            ("A*", "0-3-7-4-8-2-6-1-5-9", _SECURITY, (4.004, 1.331, 2.994, 2.48, 5.334), 2.855, 0.6935)],
    "5.8": [("Dijkstra", "0-4-8-0-3-7-0-1-6-0-2-5-9", _SECURITY_TORQUE, (2.594, 2.041, 3.956, 4.602, 5.741), 4.596,
             0.0167),
            ("GRASP", "0-4-8-2-5-0-3-7-1-6-9", _SECURITY_TORQUE, (3.145, 2.169, 3.853, 2.928, 4.763), 3.479, 115.813),
            ("A*", "0-4-8-2-5-0-3-7-1-6-9", _SECURITY_TORQUE, (3.145, 2.169, 3.853, 2.928, 4.763), 3.479, 1.1353)],
    "5.9": [("Dijkstra", "0-4-8-3-7-0-2-5-0-1-6-9", _PLANNING_TIME, (2.356, 1.881, 3.738, 3.972, 5.74), 2.946, 0.0132),
            ("GRASP", "0-4-8-3-7-1-6-2-5-9", _PLANNING_TIME, (1.991, 1.75, 3.093, 2.875, 5.298), 2.496, 139.078),
            ("A*", "0-4-8-3-7-1-6-2-5-9", _PLANNING_TIME, (1.991, 1.75, 3.093, 2.875, 5.298), 2.496, 1.674)],
    "A.1": [("Dijkstra", "0-4-8-3-7-2-5-0-1-6-9", (1.0, 0, 0, 0, 0), (2.207, 2.032, 3.676, 3.261, 5.244), 2.207, None),
            ("GRASP", "0-4-8-3-7-1-6-2-5-9", (1.0, 0, 0, 0, 0), (1.991, 1.75, 3.094, 2.875, 5.928), 1.991, None),
            ("A*", "0-2-5-1-6-0-4-8-3-7-9", (1.0, 0, 0, 0, 0), (2.164, 1.907, 3.719, 3.343, 5.738), 2.164, None)],
    "A.2": [("Dijkstra", "0-2-5-0-1-6-3-7-0-4-8-9", (0, 1.0, 0, 0, 0), (2.411, 1.679, 3.273, 4.224, 6.229), 1.679,
             None),
            ("GRASP", "0-1-5-0-2-6-4-8-3-7-9", (0, 1.0, 0, 0, 0), (3.294, 1.043, 2.895, 3.551, 6.312), 1.043, None),
            ("A*", "0-4-8-0-1-5-0-2-6-3-7-9", (0, 1.0, 0, 0, 0), (3.464, 1.141, 2.881, 4.225, 6.267), 1.141, None)],
    "A.3": [("Dijkstra", "0-4-8-0-2-5-0-3-7-0-1-6-9", (0, 0, 1.0, 0, 0), (2.594, 2.041, 3.966, 4.602, 5.741), 3.966,
             None),
            ("GRASP", "0-4-8-3-7-2-6-1-5-9", (0, 0, 1.0, 0, 0), (3.0, 1.2, 2.598, 2.791, 5.28), 2.598, None),
            ("A*", "0-4-8-3-7-0-2-6-1-5-9", (0, 0, 1.0, 0, 0), (3.149, 1.049, 2.659, 3.503, 5.777), 2.659, None)],
    "A.4": [("Dijkstra", "0-3-7-1-6-4-8-2-5-9", (0, 0, 0, 1.0, 0), (3.031, 1.869, 3.402, 2.506, 5.296), 2.506, None),
            ("GRASP", "0-3-7-4-8-2-5-1-6-9", (0, 0, 0, 1.0, 0), (3.019, 2.19, 4.053, 2.321, 5.296), 2.321, None),
            ("A*", "0-3-7-4-8-2-5-1-6-9", (0, 0, 0, 1.0, 0), (3.019, 2.19, 4.053, 2.321, 5.296), 2.321, None)],
    "A.5": [("Dijkstra", "0-4-8-0-3-7-0-2-5-0-1-6-9", (0, 0, 0, 0, 1.0), (2.594, 2.041, 3.966, 4.602, 5.741), 5.741,
             None),
            ("GRASP", "0-4-8-1-6-0-3-7-2-5-9", (0, 0, 0, 0, 1.0), (2.464, 2.1, 3.671, 3.171, 4.755), 4.755, None),
            ("A*", "0-4-8-0-3-7-2-5-1-6-9", (0, 0, 0, 0, 1.0), (2.254, 2.219, 3.885, 3.261, 5.243), 5.242, None)],
}
#: [T22] planner of each of Tables 5.2–5.4 (one scheduling instance per planner).
T22_PLANNER_TABLES = {"RRTConnect": "5.2", "BKPIECE1": "5.3", "PRM": "5.4"}
#: [T22] weight scenario (configs/sched/weights/<name>.yaml) → its table.
T22_SCENARIO_TABLES = {
    "equal": "5.5", "speed": "5.6", "security": "5.7", "security_torque": "5.8", "planning_time": "5.9",
    "only_planning_time": "A.1", "only_joint_movement": "A.2", "only_ee_distance": "A.3",
    "only_security": "A.4", "only_max_torque": "A.5",
}
