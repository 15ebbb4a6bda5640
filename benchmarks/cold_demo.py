"""The demo pipeline as a newcomer's first run: an empty JAX compilation cache, every program
compiled afresh. Writes one JSON result file.

The pipeline (``experiments/pipeline.py``, what ``make demo`` runs) runs in a fresh Python
process whose persistent compilation cache is an empty temporary folder (kept on every compile,
as ``make demo`` keeps them). That process listens to JAX's compile events
(``jax.monitoring``: tracing to a jaxpr, lowering to MLIR, XLA's backend compile, each with its
start and end) and marks each stage's start and end. Per stage it reports the wall time, the
time spent compiling (the union of the compile events' spans, so nested traces count once) and
the rest (running), the XLA programs compiled, their distinct function names and the slowest
of them; the slowest compiles of the whole run by name; and the run's outcome (docked pose, edges planned, the runs' results), so a
faster configuration can be checked to do the same work.

Run (the demo; ~7 min cold on 2 CPU cores, so on a quiet machine only):

    .venv/bin/python benchmarks/cold_demo.py

A cheaper configuration passes pipeline overrides after ``--`` and its own result file:

    .venv/bin/python benchmarks/cold_demo.py --out /tmp/cold_tiny.json -- experiment=tiny
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from uvms_jax.files import json_text, write_json

ROOT = Path(__file__).resolve().parents[1]
PIPELINE = ROOT / "experiments" / "pipeline.py"
RESULTS = ROOT / "benchmarks" / "results"
# JAX's compile events (jax._src.dispatch): tracing, lowering, and XLA's compile of one program.
TRACE, LOWER, BACKEND = ("/jax/core/compile/jaxpr_trace_duration", "/jax/core/compile/jaxpr_to_mlir_module_duration",
                         "/jax/core/compile/backend_compile_duration")
CACHE_HIT = "/jax/compilation_cache/cache_hits"
SLOWEST = 15  # compiles listed by name
SLOWEST_PER_STAGE = 5  # and per stage


# -- the pipeline's process -----------------------------------------------------------------------
def child(events_path: Path, overrides: list[str]) -> None:
    """Run the pipeline with ``overrides`` in this process, recording compile spans, cache hits
    and stage spans (``time.time()`` [s]) into ``events_path`` (JSON), whatever the outcome."""
    import jax

    rec = {"started": time.time(), "spans": [], "hits": [], "stages": [], "exit": None}
    jax.monitoring.register_event_time_span_listener(
        lambda event, start, end, **kw: rec["spans"].append([event, start, end, kw.get("fun_name", "")])
        if event in (TRACE, LOWER, BACKEND) else None)
    jax.monitoring.register_event_listener(lambda event, **kw: rec["hits"].append(time.time())
                                           if event == CACHE_HIT else None)
    from uvms_jax.pipeline.stages import STAGE_FNS  # the dict the pipeline's runner calls through

    def timed(name, fn):
        def stage(*args, **kwargs):
            t0 = time.time()
            try:
                return fn(*args, **kwargs)
            finally:
                rec["stages"].append([name, t0, time.time()])
        return stage

    for name, fn in list(STAGE_FNS.items()):
        STAGE_FNS[name] = timed(name, fn)
    sys.path.insert(0, str(PIPELINE.parent))
    sys.argv = [str(PIPELINE), *overrides]
    try:
        import runpy

        runpy.run_path(str(PIPELINE), run_name="__main__")
        rec["exit"] = 0
    except SystemExit as e:
        rec["exit"] = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
    finally:
        rec["ended"] = time.time()
        events_path.write_text(json.dumps(rec))
    sys.exit(rec["exit"])


# -- the report ----------------------------------------------------------------------------------
def _union(spans: list[tuple[float, float]]) -> float:
    """Length [s] of the union of ``(start, end)`` intervals."""
    total, reach = 0.0, -float("inf")
    for a, b in sorted(spans):
        if b > reach:
            total += b - max(a, reach)
            reach = b
    return total


def _within(spans: list, t0: float, t1: float) -> list:
    return [s for s in spans if t0 <= s[1] < t1]


def _part(spans: list, hits: list[float], t0: float, t1: float) -> dict:
    """Compile and run time, programs compiled, in ``[t0, t1)``."""
    inside = _within(spans, t0, t1)
    compile_s = _union([(max(a, t0), min(b, t1)) for _, a, b, _ in inside])
    backend = [s for s in inside if s[0] == BACKEND]
    n_hits = sum(t0 <= h < t1 for h in hits)
    return {"wall_s": round(t1 - t0, 2), "compile_s": round(compile_s, 2), "run_s": round(t1 - t0 - compile_s, 2),
            "xla_compile_s": round(sum(b - a for _, a, b, _ in backend), 2), "trace_and_lower_s": round(
                _union([(a, b) for e, a, b, _ in inside if e != BACKEND]), 2),
            "programs_compiled": len(backend) - n_hits, "persistent_cache_hits": n_hits,
            "distinct_names": len({name for *_, name in backend})}


def _slowest(spans: list, count: int) -> list[dict]:
    """The ``count`` names of the longest XLA compiles in total, with their programs."""
    by_name = collections.defaultdict(lambda: [0, 0.0])
    for _, a, b, name in (s for s in spans if s[0] == BACKEND):
        by_name[name][0] += 1
        by_name[name][1] += b - a
    slowest = sorted(by_name.items(), key=lambda kv: -kv[1][1])[:count]
    return [{"name": n, "programs": c, "xla_compile_s": round(s, 2)} for n, (c, s) in slowest]


def report(rec: dict, process_wall_s: float) -> dict:
    spans, hits = rec["spans"], rec["hits"]
    stages = {name: {**_part(spans, hits, t0, t1), "slowest_compiles": _slowest(_within(spans, t0, t1), SLOWEST_PER_STAGE)}
              for name, t0, t1 in rec["stages"]}
    first = min((t0 for _, t0, _ in rec["stages"]), default=rec["ended"])
    return {"process_wall_s": round(process_wall_s, 2),
            "before_first_stage_s": round(first - rec["started"], 2),
            "whole_run": _part(spans, hits, rec["started"], rec["ended"] + 1e-9),
            "stages": stages,
            "slowest_compiles": _slowest(spans, SLOWEST)}


def _outcome(run_dir: Path) -> dict:
    """The run's result in kind: docked pose, edges planned, the runs' results."""
    path = run_dir / "results.json"
    if not path.exists():
        return {"results_json": None}
    r = json.loads(path.read_text())
    out = {"stage_seconds": r.get("stage_seconds"), "total_seconds": r.get("total_seconds")}
    if "docking" in r:
        out.update(pose=r["docking"].get("pose"), pose_M_a=r["docking"].get("pose_M_a"))
    if "plan" in r:
        out["planned"] = {k: v for k, v in r["plan"].items() if k.endswith("_success")}
    if "hw" in r:
        out["hw"] = {k: r["hw"].get(k) for k in ("reason", "gates", "duration_s")}
    if "hover" in r:
        out["hover"] = {k: r["hover"].get(k) for k in ("status", "gates", "gates_reached")}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=None, help="result file (default: benchmarks/results/"
                    "cold_demo_<platform>.json)")
    ap.add_argument("--child", type=Path, help=argparse.SUPPRESS)
    ap.add_argument("overrides", nargs="*", help="pipeline overrides (after --), e.g. experiment=tiny")
    a = ap.parse_args()
    if a.child is not None:
        return child(a.child, a.overrides)
    with tempfile.TemporaryDirectory(prefix="cold_demo_") as tmp:
        tmp = Path(tmp)
        (tmp / "jax").mkdir()
        env = {**os.environ, "JAX_COMPILATION_CACHE_DIR": str(tmp / "jax"),
               "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS": "0"}
        env.setdefault("MUJOCO_GL", "egl")
        run_dir = tmp / "run"
        cmd = [sys.executable, __file__, "--child", str(tmp / "events.json"), "--",
               *a.overrides, f"hydra.run.dir={run_dir}"]
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, env=env, cwd=ROOT)
        wall = time.perf_counter() - t0
        rec = json.loads((tmp / "events.json").read_text())
        import jax

        res = {"command": " ".join(["python benchmarks/cold_demo.py", *(["--", *a.overrides] if a.overrides else [])]),
               "exit_status": proc.returncode, "jax": jax.__version__, "cpus": os.cpu_count(),
               "machine": platform.processor() or platform.machine(),
               "load_average_at_end": list(os.getloadavg()), **report(rec, wall), "outcome": _outcome(run_dir)}
    out = a.out or RESULTS / f"cold_demo_{jax.default_backend()}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    write_json(out, res)
    print(json_text({k: res[k] for k in ("process_wall_s", "whole_run")}))
    print(f"wrote {out}")
    sys.exit(proc.returncode)


if __name__ == "__main__":
    main()
