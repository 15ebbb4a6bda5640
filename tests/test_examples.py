"""The files in examples/ stay what the code produces, and the README's own-arm example runs."""

import runpy
from pathlib import Path

import numpy as np
import pytest

from uvms_jax import kin

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_bravo7_urdf_is_the_exported_model():
    assert (EXAMPLES / "bravo7.urdf").read_text() == kin.bravo7_urdf()
    arm = kin.from_urdf(EXAMPLES / "bravo7.urdf", tip_link="tool")
    ref = kin.bravo7()
    np.testing.assert_allclose(arm.twists, ref.twists, atol=1e-12)
    np.testing.assert_allclose(arm.T_base_tool0, ref.T_base_tool0, atol=1e-12)


@pytest.mark.slow
def test_own_arm_example_docks_beside_the_panel(capsys, monkeypatch):
    monkeypatch.chdir(EXAMPLES.parent)
    runpy.run_path(str(EXAMPLES / "own_arm.py"), run_name="__main__")
    out = capsys.readouterr().out
    assert "10 joints" in out
    assert "9/9 tool poses reached" in out
