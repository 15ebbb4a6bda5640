"""A scene is data: a scenario YAML from any folder (Hydra's search path), objects and bases by
name without node numbers, and the scheduler pairing objects with the bases the scene says
they fit."""

from __future__ import annotations

import json
import subprocess
import sys

import yaml

from _pipeline_helpers import CONFIG_DIR, ROOT


def test_scene_from_a_folder_by_names(tmp_path):
    scene = yaml.safe_load((CONFIG_DIR / "scenario" / "thesis_cage.yaml").read_text())
    objects = {o["name"]: o for o in scene["objects"]}
    bases = {b["name"]: b for b in scene["bases"]}
    # Two objects and two bases, no node numbers; the cylinder goes where a cube went, and the
    # cube on the cylinder's base: not the thesis's pairing.
    scene["objects"] = [{k: v for k, v in objects[n].items() if k != "node"} for n in ("cube1", "cylinder")]
    scene["bases"] = [{**{k: v for k, v in bases["base_cube1"].items() if k != "node"}, "fits": ["cylinder"]},
                      {**{k: v for k, v in bases["base_cylinder"].items() if k != "node"}, "fits": ["cube1"]}]
    scene["name"] = "two_swapped"
    folder = tmp_path / "configs" / "scenario"
    folder.mkdir(parents=True)
    (folder / "two_swapped.yaml").write_text(yaml.safe_dump(scene))
    run = tmp_path / "run"
    cmd = [sys.executable, "experiments/pipeline.py", f"hydra.run.dir={run}", "experiment=tiny",
           f"hydra.searchpath=[file://{tmp_path / 'configs'}]", "scenario=two_swapped", "stages=[plan,schedule,hw]"]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=1200)
    assert done.returncode == 0, done.stderr[-3000:]
    res = json.loads((run / "results.json").read_text())
    # Nodes in file order: cube1 1, cylinder 2, base_cube1 3 (fits the cylinder), base_cylinder 4
    # (fits cube1), goal 5. Every placement puts an object on a base that fits it.
    path = [int(v) for v in res["schedule"]["winner_path"].split("-")]
    assert path[0] == 0 and path[-1] == 5 and sorted(path[1:-1]) == [1, 2, 3, 4]
    placed = dict(zip(path[1:-1:2], path[2:-1:2]))
    assert placed == {1: 4, 2: 3}
    # Every move planned: start → 2 objects, each object → its base, each base → 2 objects, start, goal.
    assert res["plan"]["RRTConnect_success"] == 2 + 2 + 2 * 4
    assert res["hw"]["ok"] and res["hw"]["reason"] == "completed"
