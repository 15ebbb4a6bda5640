"""``uvms-hw`` entry point and the config group."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
import yaml

from _hw_helpers import short_plan
from uvms_jax.hw import ExecutorSettings, HwSettings, SimSettings, plan_to_dict
from uvms_jax.settings import from_mapping
from uvms_jax.cli import uvms_hw
from uvms_jax.hw.cli import build_parser, main

ROOT = Path(__file__).parents[2]
EXAMPLE = ROOT / "examples" / "thesis_plan.json"


@pytest.fixture
def plan_file(tmp_path):
    p = tmp_path / "plan.json"
    p.write_text(json.dumps(plan_to_dict(short_plan())))
    return p


def test_dry_run_example(capsys):
    assert main(["run", str(EXAMPLE), "--dry-run"]) == 0
    n_segments = len(json.loads(EXAMPLE.read_text())["segments"])
    assert f"plan ok: {n_segments} segments" in capsys.readouterr().err


def test_refused_plan_exit_2(tmp_path, capsys):
    obj = plan_to_dict(short_plan())
    obj["segments"][0]["q"][1][0] = 9.0
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(obj))
    assert main(["run", str(p), "--sim"]) == 2
    assert "joint G = 9.0000 rad outside" in capsys.readouterr().err


def test_needs_a_link_and_faults_need_sim(plan_file, capsys):
    assert main(["run", str(plan_file)]) == 2
    assert main(["run", str(plan_file), "--udp", "127.0.0.1:9", "--drop", "0.1"]) == 2
    assert "need --sim" in capsys.readouterr().err


def test_sim_run_completes(plan_file, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(plan_file), "--sim", "--out", str(out)]) == 0
    res = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert res["ok"] and res["max_gate_error_rad"] <= 0.01 and res["sim"]["limit_violations"] == 0
    assert (out / "run.csv").exists() and (out / "run.png").exists() and (out / "results.json").exists()


def test_sim_stuck_joint_exit_1(plan_file, tmp_path, capsys):
    rc = main(["run", str(plan_file), "--sim", "--stuck-joint", "B", "--gate-timeout", "0.5",
               "--no-plot", "--out", str(tmp_path)])
    assert rc == 1
    res = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert not res["ok"] and "joint B" in res["reason"]


def test_yaml_mirrors_dataclass_defaults(tmp_path, plan_file):
    cfg = yaml.safe_load((ROOT / "configs" / "hw" / "default.yaml").read_text())
    settings = from_mapping(HwSettings, cfg, "hw")
    assert settings.executor == ExecutorSettings() and settings.sim == SimSettings()
    assert set(cfg["executor"]) == {f.name for f in dataclasses.fields(ExecutorSettings)}
    assert set(cfg["sim"]) == {f.name for f in dataclasses.fields(SimSettings)}
    assert settings == HwSettings()
    with pytest.raises(ValueError, match=r"hw.executor: unknown keys \['rate'\]"):
        from_mapping(HwSettings, {"executor": {"rate": 5}}, "hw")
    with pytest.raises(ValueError, match=r"hw: unknown keys \['exec'\]"):
        from_mapping(HwSettings, {"exec": {}}, "hw")
    bad = tmp_path / "bad.yaml"
    bad.write_text("executor:\n  rate_hz: -1\n")
    assert main(["run", str(plan_file), "--dry-run", "--config", str(bad)]) == 2


def test_hw_fault_flag_parses():
    args = build_parser().parse_args(["run", "plan.json", "--sim", "--hw-fault", "d:0x04@1.5"])
    assert args.hw_fault == {"fault_joint": "D", "fault_bits": 4, "fault_after_s": 1.5}


def test_version(capsys):
    import uvms_jax

    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out.strip() == f"uvms-hw {uvms_jax.__version__}"


def _help(*command: str) -> str:
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), pytest.raises(SystemExit) as e:
        main([*command, "--help"])
    assert e.value.code == 0
    return buf.getvalue()


def test_help_shows_defaults_and_exit_codes():
    text = _help("run")
    assert f"(default: {ExecutorSettings().rate_hz}, or --config)" in text
    assert f"(default: {ExecutorSettings().speed_scale}, or --config)" in text
    assert "exit status:" in text and "2  plan refused or bad arguments" in text
    assert "(default: None)" not in text
    assert "(default: 6789)" in _help("sim")
    assert "--ros OUT" in _help("export") and "exit status:" in _help()


@pytest.mark.parametrize("bad", ["0", "1.5", "-0.2", "fast"])
def test_speed_scale_range(bad, capsys):
    with pytest.raises(SystemExit) as e:
        main(["run", str(EXAMPLE), "--dry-run", "--speed-scale", bad])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "argument --speed-scale:" in err and "(0, 1]" in err and "Traceback" not in err


def test_speed_scale_reaches_the_executor(tmp_path, capsys):
    from uvms_jax.hw.cli import _configs

    args = build_parser().parse_args(["run", "plan.json", "--speed-scale", "0.5"])
    assert _configs(args)[0] == dataclasses.replace(ExecutorSettings(), speed_scale=0.5)
    # a plan slow enough for half speed runs on the simulated arm
    obj = plan_to_dict(short_plan())
    for s in obj["segments"]:
        s["t"] = [0.0, 2.0]
    p = tmp_path / "slow.json"
    p.write_text(json.dumps(obj))
    assert main(["run", str(p), "--sim", "--speed-scale", "0.5", "--no-plot", "--out", str(tmp_path / "o")]) == 0
    assert json.loads(capsys.readouterr().out.strip().splitlines()[-1])["ok"]


def test_hovering_run_on_the_simulated_arm(plan_file, tmp_path, capsys):
    """``--hover``: the whole-body controller between the plan and the simulated arm of a vehicle
    hovering in a 0.3 m/s current; every gate on the tool within 10 mm, the plan's 4 gates."""
    out = tmp_path / "out"
    assert uvms_hw(["run", str(plan_file), "--hover", "--current", "0.3", "0", "0", "--no-plot", "--out", str(out)]) == 0
    res = json.loads((out / "results.json").read_text())
    hover = res["hover"]
    assert res["ok"] and res["gates"] == 4 and res["sim"]["limit_violations"] == 0
    assert hover["driver"] == "BPL executor, whole-body controller" and hover["status"] == "completed"
    assert hover["current_m_s"] == [0.3, 0.0, 0.0] and hover["max_drift_m"] > 0
    assert len(hover["gate_tool_error_m"]) == 4 and max(hover["gate_tool_error_m"]) <= 0.01
    assert hover["thrust_limited_periods"] == 0 and hover["joint_limited_periods"] is not None


def test_hovering_flags_need_hover_and_the_controllers_rate(plan_file, tmp_path, capsys):
    assert main(["run", str(plan_file), "--sim", "--current", "0.3", "0", "0", "--out", str(tmp_path / "a")]) == 2
    assert "--current need --hover" in capsys.readouterr().err
    assert uvms_hw(["run", str(plan_file), "--hover", "--rate", "100", "--out", str(tmp_path / "b")]) == 2
    assert "50 Hz" in capsys.readouterr().err
    assert main(["run", str(plan_file), "--hover", "--out", str(tmp_path / "b")]) == 2  # hw.cli alone: no vehicle
    assert "run it as uvms-hw" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:  # argparse: one link
        uvms_hw(["run", str(plan_file), "--hover", "--udp", "127.0.0.1:9"])
    assert e.value.code == 2 and "not allowed with argument --hover" in capsys.readouterr().err
    assert not (tmp_path / "b").exists()
    text = build_parser()._subparsers._group_actions[0].choices["run"].format_help()
    assert "--hover" in text and "whole-body controller" in text and "--current VX VY VZ" in text
