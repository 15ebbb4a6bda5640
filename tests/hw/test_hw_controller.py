"""A joint controller between the plan and the arm (Executor(controller=...)) on the simulated
Bravo 7 with a fixed base.

Oracles: the plan's waypoints written out (the rows a controller is given end each move on its
waypoint), the joint table's limits for every demand on the wire, and the hold packets the
executor sends when it stops.
"""

from __future__ import annotations

import numpy as np

from _hw_helpers import BRAVO7, Q0, Q1, SimRun, assert_within_limits, short_plan
from test_hw_executor import last_packets_are_hold
from uvms_jax.hw import Executor, ExecutorSettings

ARM = slice(0, 6)
BAD_ROW = 20  # the row at which the faulty controller asks for a demand past a limit


class Follower:
    """Sends the plan's rows as they are; counts its calls; optionally misbehaves."""

    def __init__(self, overshoot: bool = False, never_gates: bool = False) -> None:
        self.overshoot, self.never_gates = overshoot, never_gates
        self.rows, self.demanded, self.stopped = None, [], 0

    def prepare(self, q_plan, period):
        self.rows, self.period = np.asarray(q_plan), period

    def demand(self, k, q):
        self.demanded.append(k)
        out = self.rows[k].copy()
        if self.overshoot and k == BAD_ROW:
            out[0] = BRAVO7[0].upper + 0.1
        return out

    def gate(self, k, q):
        return "never" if self.never_gates else None

    def stop(self):
        self.stopped += 1


def _run(controller) -> tuple[SimRun, object]:
    run = SimRun()
    run.executor = Executor(run.client, ExecutorSettings(), sleep=run.clock.sleep, controller=controller)
    return run, run.executor.run(short_plan())


def test_a_controller_following_the_rows_completes_on_the_waypoints():
    ctl = Follower()
    run, res = _run(ctl)
    assert res.ok, res.reason
    assert len(res.gates) == 4 and ctl.stopped == 1
    assert ctl.period == 1.0 / ExecutorSettings().rate_hz and ctl.rows.shape[1] == 6
    # The rows start at the arm's start and hold each waypoint at the end of its move: Q0 (the
    # start), Q1 (out), Q1 (the jaws' move), Q0 (back).
    np.testing.assert_allclose(ctl.rows[0], Q0)
    np.testing.assert_allclose(ctl.rows[-1], Q0)
    assert any(np.allclose(r, Q1) for r in ctl.rows)
    assert ctl.demanded == sorted(ctl.demanded) and ctl.demanded[-1] == len(ctl.rows) - 1
    assert_within_limits(run.sent_packets())
    assert run.arm.limit_violations == 0


def test_a_demand_past_a_limit_is_refused_and_the_run_stops_holding():
    ctl = Follower(overshoot=True)
    run, res = _run(ctl)
    assert not res.ok and "LimitError" in res.reason and "outside limits" in res.reason
    assert ctl.demanded[-1] == BAD_ROW and ctl.stopped == 1
    assert_within_limits(run.sent_packets())  # nothing past a limit reached the wire
    assert run.arm.limit_violations == 0
    assert last_packets_are_hold(run)


def test_a_gate_the_controller_does_not_pass_times_out_with_its_reason():
    run, res = _run(Follower(never_gates=True))
    assert not res.ok and "gate not reached" in res.reason and "never" in res.reason
    assert last_packets_are_hold(run)
