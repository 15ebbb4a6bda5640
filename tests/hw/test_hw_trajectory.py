"""Synchronised moves: exact endpoints, common arrival, limits respected (finite differences)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uvms_jax.hw import synchronised_move

LIMIT_RTOL = 1e-3  # finite differences on the sampling grid overshoot the analytic peak slightly

vec = st.lists(st.floats(0.0, 3.5, allow_nan=False), min_size=6, max_size=6)
# A duration a plan can ask for: none, or at least a millisecond (a subnormal duration makes the
# test's own sampling step underflow to zero).
durations = st.one_of(st.just(0.0), st.floats(1e-3, 5.0))


@settings(max_examples=80, deadline=None)
@given(q0=vec, q1=vec, min_dur=durations,
       v=st.floats(0.1, 2.0), a=st.floats(0.1, 5.0))
def test_move_properties(q0, q1, min_dur, v, a):
    vmax = np.full(6, v) * np.linspace(1, 2, 6)
    amax = np.full(6, a)
    m = synchronised_move(np.array(q0), np.array(q1), vmax, amax, min_dur)
    assert m.duration >= min_dur
    assert 0 < m.accel_fraction <= 0.5
    t = np.linspace(0, m.duration, 801)
    q = np.array([m.sample(x)[0] for x in t])
    np.testing.assert_allclose(q[0], q0, atol=1e-12)
    np.testing.assert_allclose(q[-1], q1, atol=1e-12)
    if m.duration > 0:
        dt = t[1] - t[0]
        vel = np.diff(q, axis=0) / dt
        assert np.all(np.abs(vel) <= vmax * (1 + LIMIT_RTOL) + 1e-9)
        acc = np.diff(vel, axis=0) / dt
        assert np.all(np.abs(acc) <= amax * (1 + 0.05) + 1e-6)  # kinks at phase changes
        # synchronised: every joint covers the same fraction of its distance at every time
        d = np.array(q1) - np.array(q0)
        k = np.abs(d) > 1e-6
        if k.any():
            frac = (q[:, k] - np.array(q0)[k]) / d[k]
            assert np.allclose(frac, frac[:, :1], atol=1e-9)
        # stays between the endpoints
        lo, hi = np.minimum(q0, q1), np.maximum(q0, q1)
        assert np.all(q >= lo) and np.all(q <= hi)


def test_minimum_time_is_tight():
    m = synchronised_move(np.zeros(2), np.array([1.0, 0.2]), np.array([0.5, 0.5]), np.array([1.0, 1.0]))
    assert m.duration == pytest.approx(1.0 / 0.5 + 0.5 / 1.0)  # trapezoid: D/v + v/a
    m = synchronised_move(np.zeros(1), np.array([0.1]), np.array([0.5]), np.array([1.0]))
    assert m.duration == pytest.approx(2 * np.sqrt(0.1))  # triangle
    assert m.sample(m.duration / 2)[1][0] == pytest.approx(np.sqrt(0.1))


def test_zero_move_and_errors():
    m = synchronised_move(np.ones(3), np.ones(3), np.ones(3), np.ones(3), 0.7)
    assert m.duration == 0.7 and np.all(m.sample(0.3)[1] == 0)
    with pytest.raises(ValueError, match="finite"):
        synchronised_move(np.array([np.nan]), np.zeros(1), np.ones(1), np.ones(1))
    with pytest.raises(ValueError, match="positive"):
        synchronised_move(np.zeros(1), np.ones(1), np.zeros(1), np.ones(1))
    with pytest.raises(ValueError, match="shapes"):
        synchronised_move(np.zeros(2), np.ones(1), np.ones(1), np.ones(1))
