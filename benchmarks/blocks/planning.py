"""Report blocks of planning: the thesis cage, MotionBenchMaker on the CPU, with VAMP, and on a GPU."""

from __future__ import annotations

from uvms_jax.text import md_table
from blocks._format import _load, _ms

__all__ = ["plan_benchmark", "mbm_benchmark", "mbm_summary", "mbm_gpu"]


def plan_benchmark() -> str:
    d = _load("plan_cpu.json")
    rows = []
    for checker, c in d["checkers"].items():
        for planner, p in c["planners"].items():
            rows.append([checker, planner, f"{p['success']}/{p['edges']}", f"{p['revalidated']}/{p['edges']}",
                         f"{p['median_ms']:.1f}", f"{p['mean_ms']:.1f}", f"{p['max_ms']:.1f}", f"{p['graph_wall_s']:.2f}"])
    v = d["validity_checks"]
    checks = [["MuJoCo `is_valid(q)` (argument checks)", f"{v['mujoco_single_is_valid_per_s']:,.0f}"],
              ["MuJoCo OMPL callback (`state_validator`)", f"{v['mujoco_ompl_callback_per_s']:,.0f}"],
              ["MuJoCo `is_valid_batch(Q)`", f"{v['mujoco_batched_is_valid_per_s']:,.0f}"],
              ["sphere checker, one call over all states", f"{v['spheres_one_call_per_state_per_s']:,.0f}"]]
    sp, mj = d["checkers"]["spheres"], d["checkers"].get("mujoco")
    steps = sp["planners"]["RRTConnect"]["steps_s"]
    return (f"`{d['command']}` ({d['device']}; `benchmarks/results/plan_cpu.json`): {d['budget_s']:g} s per-edge budget, "
            f"the straight-segment shortcut {'on' if d['straight_shortcut'] else 'off (each planner its own path, simplified)'}."
            "\n\n" + md_table(["checker", "planner", "planned", "re-checked OK", "median [ms]", "mean [ms]", "max [ms]",
                                "whole graph [s]"], rows)
            + f"\n\nWhole task graph with all three planners: {sp['graph_all_planners_wall_s']:.2f} s with the sphere checker"
            + (f" against {mj['graph_all_planners_wall_s']:.2f} s with MuJoCo state by state" if mj else "")
            + ". Where RRTConnect's graph time goes (spheres, `steps_s`): "
            + ", ".join(f"{k.replace('_', ' ')} {t:.3f} s" for k, t in steps.items())
            + f". IK targets (one batched `kin.numeric_ik` call, compilation included, warm cache) "
            f"{d['ik_targets_s_incl_compile']:.1f} s; the sphere checker's Numba compile or cache load "
            f"{d['numba_compile_or_cache_load_s']:.2f} s.\n\nValidity checks (uniform random configurations, "
            f"{v['valid_fraction_uniform']:.0%} valid):\n\n" + md_table(["call", "checks/s"], checks) + "\n")


def mbm_benchmark() -> str:
    """The MotionBenchMaker Panda set on the CPU: the query path beside OMPL with MuJoCo."""
    d = _load("mbm_cpu.json")
    peer = "ompl_mujoco" in next(iter(d["families"].values()))
    vamp = "vamp" in next(iter(d["families"].values()))
    rows = []
    for family, f in d["families"].items():
        q = f["query"]
        row = [family, str(q["valid"]), f"{q['solved']}", _ms(q["median_ms"]), _ms(q["p95_ms"]), _ms(q["max_ms"]),
               str(q["rechecked_free"])]
        if peer:
            o = f["ompl_mujoco"]
            row += [str(o["solved"]), str(o["rechecked_free"]), _ms(o["median_ms"]), _ms(o["p95_ms"]), _ms(o["max_ms"])]
        if vamp:
            v = f["vamp"]
            row += [str(v["solved"]), str(v["rechecked_free"]), str(v["in_limits"]), _ms(v["median_ms"]),
                    _ms(v["p95_ms"]), _ms(v["max_ms"]), f"{v['own_median_ms'] * 1e3:.0f}"]
        rows.append(row)
    t = d["query_total"]
    header = ["family", "valid", "solved", "median [ms]", "p95 [ms]", "max [ms]", "re-checked free"]
    if peer:
        header += ["OMPL+MuJoCo solved", "re-checked free", "median [ms]", "p95 [ms]", "max [ms]"]
    if vamp:
        header += ["VAMP solved", "re-checked free", "in the URDF's limits", "median [ms]", "p95 [ms]", "max [ms]",
                   "its own clock, median [µs]"]
    invalid = ", ".join(f"{n} {reason}" for reason, n in sorted(d["invalid"].items()))
    checks = d["state_check"]
    spheres = sorted(c["spheres_us"] for c in checks.values())
    verdict = sorted(c["verdict_us"] for c in checks.values())
    mujoco = sorted(c["mujoco_us"] for c in checks.values())
    maybe = sorted(c["maybe_fraction"] for c in checks.values())
    return (f"`{d['command']}` ({d['device']}, 2 cores; `benchmarks/results/mbm_cpu.json`): the Panda with its own "
            f"hand and fingers from its URDF ({d['n_spheres']} covering spheres, largest excess "
            f"{d['sphere_excess_m'] * 1e3:.0f} mm), fingers at {d['opening_m']:g} m (the requests' "
            f"{d['request_opening_m']:g} m is past the URDF's limit), {d['budget_s']:g} s budget per problem, "
            f"a failure counted at the whole budget. Every returned path re-checked by MuJoCo with the real "
            f"fingers, densified to {d['recheck_rad']:g} rad.\n\n" + md_table(header, rows)
            + f"\n\nAll families: {t['solved']}/{t['valid']} model-valid problems solved ({t['success_rate']:.1%}), "
            f"median {_ms(t['median_ms'])} ms, p95 {_ms(t['p95_ms'])} ms, {t['rechecked_free']} of the {t['solved']} "
            f"returned paths free for MuJoCo. "
            f"Invalid in the model (MuJoCo on the description's geometry; limits in float64): {invalid}. "
            f"Numba compile or cache load {d['compile_s']:.1f} s before any timing.\n\n" + _mbm_vamp(d) +
            f"Per state, one call over 4096 uniform random configurations (range over the seven families' first "
            f"worlds): the spheres and pair tables alone {spheres[0]:.2f}–{spheres[-1]:.2f} µs "
            f"({maybe[-1]:.0%} or fewer "
            f"undecided), the verdicts with MuJoCo settling those {verdict[0]:.2f}–{verdict[-1]:.2f} µs, MuJoCo "
            f"alone {mujoco[0]:.1f}–{mujoco[-1]:.1f} µs.\n")


def _mbm_vamp(d: dict) -> str:
    """The VAMP peer's totals in the MotionBenchMaker run, if it ran (docs/planning.md, 'VAMP as a peer')."""
    if "vamp_total" not in d:
        return ""
    v = d["vamp_total"]
    return (f"VAMP (its own 59-sphere model, fingers at 0.065 m; docs/planning.md, \"VAMP as a peer\"): "
            f"{v['solved']}/{v['valid']} solved, median {_ms(v['median_ms'])} ms per call from Python and "
            f"{v['own_median_ms'] * 1e3:.0f} µs by its own clock, {v['rechecked_free']} of the {v['solved']} paths free "
            f"for MuJoCo, a finger in every contact of {v['fingers_only_hits']} of the others, "
            f"{v['in_limits']} inside the URDF's limits; its model calls {v['model_invalid']} of the problems "
            f"invalid.\n\n")


def mbm_summary() -> str:
    """docs/planning.md's summary of the MotionBenchMaker run (``benchmarks/mbm.py``)."""
    d = _load("mbm_cpu.json")
    t = d["query_total"]
    peer = [f["ompl_mujoco"] for f in d["families"].values() if "ompl_mujoco" in f]
    line = (f"{t['solved']}/{t['valid']} model-valid problems solved ({t['success_rate']:.1%}), median "
            f"{_ms(t['median_ms'])} ms and p95 {_ms(t['p95_ms'])} ms per problem, {t['rechecked_free']} of the "
            f"{t['solved']} returned paths free for MuJoCo at {d['recheck_rad']:g} rad")
    if peer:
        line += (f"; OMPL's RRT-Connect with MuJoCo's checks solved {sum(p['solved'] for p in peer)} with family "
                 f"medians of {_ms(min(p['median_ms'] for p in peer))}–{_ms(max(p['median_ms'] for p in peer))} ms")
    vamp = [f["vamp"] for f in d["families"].values() if "vamp" in f]
    if vamp:
        line += (f"; VAMP solved {sum(v['solved'] for v in vamp)} with family medians of "
                 f"{_ms(min(v['median_ms'] for v in vamp))}–{_ms(max(v['median_ms'] for v in vamp))} ms, "
                 f"{sum(v['rechecked_free'] for v in vamp)} of its paths free for MuJoCo")
    invalid = ", ".join(f"{n} {reason}" for reason, n in sorted(d["invalid"].items()))
    return (line + f". Invalid in the model: {invalid} (`benchmarks/results/mbm_cpu.json`, {d['device']}, "
            f"{d['budget_s']:g} s budget).\n")


def mbm_gpu() -> str:
    """The MotionBenchMaker Panda set in one batched call on a GPU (``benchmarks/mbm_gpu.py``)."""
    d = _load("mbm_gpu_h100.json")
    t = d["totals"]
    rows = [[f.removesuffix("_panda"), str(v["problems"]), str(v["endpoints_free"]), str(v["solved"]),
             str(v["rechecked_free"])] for f, v in d["families"].items()]
    return (f"`python benchmarks/mbm_gpu.py --device gpu` ({d['device']}, jax {d['jax']}, {d['dtype']}; "
            f"`benchmarks/results/mbm_gpu_h100.json`): all {d['n_problems']} problems in one jitted call, "
            f"{d['n_spheres']} covering spheres, no MuJoCo on the GPU (a state the spheres cannot tell counts as "
            f"a collision). Compile {d['compile_s']:.1f} s, run {min(d['run_s']):.0f} s; {t['solved']} solved, "
            f"every one free for MuJoCo at {d['settings']['resolution']:g} rad; {t['endpoints_free']} have a start "
            f"and goal the spheres call free.\n\n"
            + md_table(["family", "problems", "ends free (spheres)", "solved", "re-checked free"], rows) + "\n")
