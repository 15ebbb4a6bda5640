"""The README's own-arm example runs."""

import runpy
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.slow
def test_own_arm_example_docks_beside_the_panel(capsys, monkeypatch):
    monkeypatch.chdir(EXAMPLES.parent)
    runpy.run_path(str(EXAMPLES / "own_arm.py"), run_name="__main__")
    out = capsys.readouterr().out
    assert "10 joints" in out
    assert "9/9 tool poses reached" in out
