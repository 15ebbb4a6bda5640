"""uvms_jax.progress: whole lines in a log, the final count always reported."""

import io
import time

from uvms_jax import progress


def _lines(**kw) -> list[str]:
    f = io.StringIO()
    for _ in progress.bar(range(20), desc="plan", unit="edge", file=f, **kw):
        time.sleep(0.01)
    return f.getvalue().splitlines()


def test_log_lines_are_whole_and_periodic():
    lines = _lines(log_interval_s=0.05)
    text = "\n".join(lines)
    assert "\r" not in text
    assert len(lines) >= 3  # the first, some in between, the last
    assert lines[-1].startswith("plan: 20/20 edge (100 %)")


def test_quiet_when_fast_but_final_count_reported():
    lines = _lines(log_interval_s=60.0)
    assert lines[-1].startswith("plan: 20/20 edge (100 %)")
    assert len(lines) <= 2


def test_manual_bar_without_total():
    f = io.StringIO()
    with progress.bar(desc="hw", unit="seg", file=f) as b:
        b.update(3)
    assert f.getvalue().splitlines()[-1].startswith("hw: 3 seg,")
