"""The intervention's wall time per arm: ``experiments/pipeline.py`` (docking, planning,
scheduling, execution on the simulated arm) with the Bravo 7 and with the real arms of
``examples/arms.yaml``, each in its own process, at the demo's sizes (``--tiny``: the test
preset). Reports per arm the stages' wall and CPU seconds, the process's wall time (imports and
XLA compilation included: each process compiles afresh, no persistent cache), edges planned,
gates reached. Prints one JSON object.

    .venv/bin/python benchmarks/pipeline_arms.py [--tiny] [--capsules] [--arms bravo7 ur5]
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

from uvms_jax.files import json_text

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE_ARMS = yaml.safe_load((ROOT / "examples" / "arms.yaml").read_text())
STAGES = "[docking,plan,schedule,hw]"


def _card(arm: str, folder: Path, capsules: bool) -> str:
    """The arm's card: a shipped name, or a card written for an example-robot-data arm."""
    if arm not in EXAMPLE_ARMS["arms"]:
        return arm
    robots = importlib.metadata.distribution("example-robot-data").locate_file(
        "cmeel.prefix/share/example-robot-data/robots")
    settings = dict(EXAMPLE_ARMS["arms"][arm], gripper=EXAMPLE_ARMS["jaws"])
    if capsules:
        settings["collision"] = "capsules"
    settings["description"] = str(Path(robots) / settings["description"])
    path = folder / f"{arm}.yaml"
    path.write_text(yaml.safe_dump(settings))
    return str(path)


def run_arm(arm: str, tiny: bool, capsules: bool, folder: Path) -> dict:
    out = folder / f"run_{arm}"
    overrides = [f"hydra.run.dir={out}", f"stages={STAGES}", f"scenario.arm.card={_card(arm, folder, capsules)}"]
    if arm != "bravo7":  # the thesis's start pose and target choice are the Bravo 7's
        overrides += ["scenario.start_q=null", "plan.ik.select=nearest_start"]
    if tiny:
        overrides.append("experiment=tiny")
    env = {k: v for k, v in os.environ.items() if not k.startswith("JAX_COMPILATION_CACHE")}
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "experiments/pipeline.py", *overrides], cwd=ROOT, env=env,
                          capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        return {"arm": arm, "error": done.stderr.strip().splitlines()[-1], "process_wall_s": wall}
    res = json.loads((out / "results.json").read_text())
    return {"arm": arm, "dof": res["arm"]["dof"], "process_wall_s": wall, "stages_wall_s": res["total_seconds"],
            "stage_wall_s": res["stage_seconds"], "stage_cpu_s": res["stage_cpu_seconds"],
            "edges_planned": res["plan"]["RRTConnect_success"], "schedule": res["schedule"]["winner_path"],
            "run": res["hw"]["reason"], "gates": res["hw"]["gates"], "executed_s": res["hw"]["duration_s"]}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tiny", action="store_true", help="the test preset (experiment=tiny) instead of the demo's sizes")
    p.add_argument("--capsules", action="store_true",
                   help="the example arms with capsules along their links instead of their files' collision geometry")
    p.add_argument("--arms", nargs="+", default=["bravo7", *EXAMPLE_ARMS["arms"]])
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        runs = [run_arm(arm, args.tiny, args.capsules, Path(tmp)) for arm in args.arms]
    print(json_text({"benchmark": "pipeline_arms", "command": " ".join(["python benchmarks/pipeline_arms.py", *sys.argv[1:]]),
                      "preset": "tiny" if args.tiny else "demo", "stages": STAGES,
                      "collision": "capsules" if args.capsules else "description",
                      "machine": {"cpus": os.cpu_count(), "processor": platform.processor() or platform.machine()},
                      "runs": runs}))


if __name__ == "__main__":
    main()
