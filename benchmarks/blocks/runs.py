"""Report blocks of whole runs: the demo, the papers, arms through the pipeline, the hardware runner, scheduling, the suite."""

from __future__ import annotations

from uvms_jax.text import md_table
from blocks._format import _batch, _load, _minutes, _reproduction, _sci

__all__ = ["demo", "cold_demo", "papers", "pipeline_arms", "own_arm", "weights_sweep", "hw_runner", "hw_acceptance", "sched_benchmark", "test_suite", "test_suite_isa"]


def demo() -> str:
    d = _load("demo_cpu.json")
    sur, dock, pl, sch, hw, base = (d[k] for k in ("surrogate", "docking", "plan", "schedule", "hw", "baseline"))
    t = d["stage_seconds"]
    same = [name for name in ("exact", "astar", "grasp") if abs(sch[f"{name}_cost"] - sch["winner_cost"]) < 1e-9]
    label = {"exact": "exact", "astar": "A*", "grasp": "GRASP"}
    x, y, z = pl["base_xyz"]
    docked, fixed = base["docked"], base["fixed"]
    rows = [
        ["surrogate", f"map learned from {sur['n_train_samples']} tool poses in the arm's base frame "
                      f"({sur['n_test_samples']} held out); held-out RMSE of w {sur['rmse_w']:.4f} (largest w "
                      f"{sur['w_range']:.3f})", f"{t['surrogate']:.1f}"],
        ["docking", f"GA runs: best {dock['ga_best_fitness']:.3f} (M_a {dock['ga_best_M_a']:.4f}), worst "
                    f"{dock['ga_ratio_to_grid_min'] * dock['grid_fitness']:.2f}; multistart grid search: **{dock['grid_fitness']:.3f} "
                    f"(M_a {dock['pose_M_a']:.4f})**, chosen ({dock['pose_source']}); the map's route (its GA "
                    f"proposes, the analytic fitness confirms and refines): {dock['map_best_fitness']:.3f}, a loss of "
                    f"optimum of {dock['map_loss_of_optimum']:.2%} with {dock['map_analytic_evaluations']} analytic "
                    f"evaluations against the analytic search's {dock['analytic_evaluations']} "
                    f"({dock['map_evaluation_ratio']:.0f}× fewer)", f"{t['docking']:.1f}"],
        ["plan", f"arm base at ({x:.3f}, {y:.3f}, {z:.3f}) m under the docked vehicle; {pl['RRTConnect_success']} edges "
                 f"planned and re-checked by MuJoCo, median RRTConnect {pl['RRTConnect_median_ms']:.1f} ms",
         f"{t['plan']:.1f}"],
        ["schedule", f"{' = '.join(label[n] for n in same)}: {sch['winner_path']}, cost {sch['winner_cost']:.3f} "
                     f"(greedy {sch['greedy_cost']:.3f}; costs are normalised over this run's metrics, planning times "
                     "included, so they and the winner move from run to run)", f"{t['schedule']:.1f}"],
        ["hw", f"{hw['status']} on the simulated arm: {hw['gates']} gates within 0.01 rad (max "
               f"{hw['max_gate_error_rad']:.3g} rad), {hw['duration_s']} s of simulated time, "
               f"{hw['sim']['limit_violations']} demands outside the limits, `run.mp4`", f"{t['hw']:.1f}"],
        ["baseline", f"the thesis's cage-top mount: M_a {fixed['M_a']:.4f} (docked: {docked['M_a']:.4f}), completed in "
                     f"{fixed['executed_s']} s (docked: {docked['executed_s']} s)", f"{t['baseline']:.1f}"],
    ]
    if "hover" in d:
        def run(label, m):
            driver = "" if m["driver"] in label else f" ({m['driver']})"
            return (f"{label}{driver}: {m['status']}, {m['gates_reached']}/{m['gates']} gates passed, the tool "
                    f"within 10 mm at {m['gates_tool_within_tolerance']}, drift ≤ {1e3 * m['max_drift_m']:.0f} mm, tool "
                    f"≤ {1e3 * m['max_tool_error_m']:.0f} mm, tilt ≤ {m['max_tilt_deg']:.1f}°, thrust ≤ "
                    f"{m['peak_thrust_N']:.0f} N")
        runs = d["hover"]["runs"]
        rows.insert(-1, ["hover", "the plan executed with the vehicle hovering at the docked pose on thrusters; "
                         + "; ".join(run(label, m) for label, m in runs.items()), f"{t['hover']:.1f}"])
    change = fixed["executed_s"] / docked["executed_s"] - 1
    return (f"Pipeline {d['total_seconds']:.1f} s (compilation cache warm):\n\n"
            + md_table(["stage", "result", "wall [s]"], rows)
            + f"\n\nSo the docked arm is more dexterous over the targets (M_a {docked['M_a'] / fixed['M_a'] - 1:+.0%}), and the "
            f"fixed mount's run is\n{abs(change):.0%} {'shorter' if change < 0 else 'longer'}: from the cage top the arm's "
            f"tool travels {fixed['ee_distance_m']:.1f} m against {docked['ee_distance_m']:.1f} m docked.\n")


def papers() -> str:
    """The papers' summary of README.md, from the record of ``make papers`` (docs/reproduction.json)."""
    from uvms_jax.papers import D16_NETWORKS, T22_TABLES

    rec = _reproduction()["sections"]
    dk, dx, th = rec["docking"], rec["surrogate"], rec["thesis"]
    # The paper's Jacobian (spatial form, eq. 6) leads; ours (geometric) follows.
    nets, ours = dx["networks"]["spatial"], dx["networks"]["geometric"]
    batches = sorted(nets["ffbn_w"]["speedup"], key=int)

    def speedups(name):  # "4.2× / 19× / 0.26×", one per batch size
        return " / ".join(f"{r:.2f}×" if r < 1 else f"{r:.1f}×" if r < 10 else f"{r:.0f}×"
                          for r in (nets[name]["speedup"][b] for b in batches))

    def net(name, of=nets):
        n = of[name]
        return f"{n['units']} units, {100 * n['max_rel_test_error']:.2f} %" + ("" if n["met_goal"] else " (goal not met)")

    t55 = {r[0]: r for r in T22_TABLES["5.5"]}
    eq = th["eq41"]
    return (
        f"- **Docking** ([theory §3](docs/theory.md#3-docking-optimisation), paper Tables 3–4, Figs 9–10): "
        f"our {dk['ga_runs']} GA\n"
        f"  poses lie on an edge of the quarter nearest the start (x or y within 1 cm of 0), the paper's near its "
        f"diagonal; the paper's poses face the task centre "
        f"within\n  {dk['heading_min']:.0f}–{dk['heading_max']:.0f}° of the bearing, ours do not "
        f"({dk['ga_heading_min']:.0f}–{dk['ga_heading_max']:.0f}°: with the tool yaw tied to the heading, M_a hardly "
        f"depends on ψ\n  and the distance term sets it; with ψ fixed towards the centre our fitness is "
        f"{dk['facing_loss']:.1f} % lower). Zero-w share of the\n  task area: our optimum {dk['zero_ours']:.1f} %, the "
        f"ill-placed pose {dk['zero_ill']:.1f} % (paper's Figs 9–10: \"a quite small area\", a large one). The paper's\n"
        f"  M_a (0.134–0.181) is out of reach of the arm as stated: it exceeds the largest w of any 6 × 6 Jacobian of\n"
        f"  that arm ({dk['bound']:.4f}), and under our frames every Table 3 pose has M_a = 0 (the far corner lies "
        f"beyond l1 + l2);\n  our GA runs' M_a is {dk['ga_m_min']:.4f}–{dk['ga_m_max']:.4f}. The readings tried "
        "and Table 4 by FK are in docs/reproduction/docking.md.\n"
        f"- **Surrogates** ([theory §4](docs/theory.md#4-surrogates), paper Tables 4–5), with the paper's Jacobian "
        f"(spatial form, eq. 6):\n  FFBN-w {net('ffbn_w')}; "
        f"FFBN-KCI {net('ffbn_kci')}; RBFN-w {net('rbfn_w')} (paper: {D16_NETWORKS['ffbn_w']['hidden_units']}, "
        f"{D16_NETWORKS['ffbn_kci']['hidden_units']}, {D16_NETWORKS['rbfn_w']['hidden_units']} units; all < 2 %); "
        f"against the project's fastest\n  analytic path (the fused `indices.manipulability_of` / `kci_of` kernel, "
        f"same run,\n  preset \"{dx['preset']}\", {dx['device']}), at {' / '.join(_batch(int(b)) for b in batches)} "
        f"inputs, the FFBN runs at {speedups('ffbn_w')} its speed for w and {speedups('ffbn_kci')} for KCI,\n  "
        f"RBFN-w at {speedups('rbfn_w')} and RBFN-KCI at {speedups('rbfn_kci')} (the paper timed Matlab LU/SVD "
        f"on the symbolic Jacobian and gives one time per network type; above 1e5 inputs both sides ran in chunks "
        f"through `lax.map`, which slows each chunk several-fold: docs/benchmarks/surrogates.md). FFBN-KCI {dx['ffbn_kci']} in that run; "
        f"with\n  {dx['sizes_n_train']} training samples (ours; the paper gives no training-set size; "
        f"`{dx['sizes_file']}`) it {dx['sizes_result']}. "
        f"With our\n  geometric Jacobian KCI ignores the vehicle's joints and FFBN-KCI needs {net('ffbn_kci', ours)}.\n"
        f"- **Scheduling** ([theory §5](docs/theory.md#5-pick-and-place-scheduling), thesis Table 5.5, eq. 4.1): greedy "
        f"gives the\n  thesis's schedule {eq['greedy']['path']} / {eq['greedy']['cost']:.4f} in "
        f"{eq['greedy']['ms']:.3g} ms (thesis {t55['Dijkstra'][5]:g} ms on its own instance); GRASP\n  (1000 "
        f"iterations, {eq['grasp/deliveries']['ms']:.3g} ms; thesis {t55['GRASP'][5]:g} ms), A* ({eq['astar']['ms']:.3g} ms; "
        f"thesis {t55['A*'][5]:g} ms) and the exact DP find the\n  optimum {eq['exact']['cost']:.4f}. With the thesis's "
        f"own local search (`sched.grasp.local_search=thesis`) GRASP(1000)\n  finds it in "
        f"{eq['grasp/thesis']['optimal_of_20']} of 20 runs.\n")


def pipeline_arms() -> str:
    d = _load("pipeline_arms_cpu.json")
    rows = []
    for r in d["runs"]:
        if "error" in r:
            rows.append([r["arm"], "", "", "", "", "", "", f"{r['process_wall_s']:.1f}", "—", "—", f"stopped: {r['error']}"])
            continue
        t = r["stage_wall_s"]
        rows.append([r["arm"], str(r["dof"]), *(f"{t[k]:.1f}" for k in ("docking", "plan", "schedule", "hw")),
                     f"{r['stages_wall_s']:.1f}", f"{r['process_wall_s']:.1f}", f"{r['edges_planned']}/34", r["schedule"],
                     f"{r['run']}, {r['gates']} gates, {r['executed_s']:.1f} s"])
    return (f"`{d['command']}` ({d['machine']['cpus']}-core CPU; `benchmarks/results/pipeline_arms_cpu.json`; preset "
            f"{d['preset']}, collision geometry from the {d['collision']}):\n\n"
            + md_table(["arm", "joints", "docking [s]", "plan [s]", "schedule [s]", "hw [s]", "stages [s]", "process [s]",
                      "edges planned", "schedule", "executed (simulated)"], rows) + "\n")


def own_arm() -> str:
    """README's own-arm example: what it prints and how long it takes (``benchmarks/own_arm.py``)."""
    d = _load("own_arm_cpu.json")
    return (f"prints `{d['printed'][0]}` and `{d['printed'][-1]}`, in {d['wall_s']:.0f} s on a "
            f"{d['cpu_count']}-core CPU with imports and compilation (`python benchmarks/own_arm.py`, "
            f"`benchmarks/results/own_arm_cpu.json`).\n")


def weights_sweep() -> str:
    """README's weight-sensitivity sweep: its gathered table and time (``benchmarks/weights_sweep.py``)."""
    d = _load("weights_sweep_cpu.json")
    return ("```bash\n" + "\n".join(d["commands"]) + "\n```\n\n"
            "gives five job folders `multirun/weights/0 … 4` (each with `table.md`, `results.json`,\n"
            "`route.png`, `schedule_edges.json`) and one table, `multirun/weights/gathered.md` (every\n"
            f"column in `gathered.csv`); both commands take {d['wall_s']:.0f} s on a {d['cpu_count']}-core CPU "
            "(`python benchmarks/weights_sweep.py`, `benchmarks/results/weights_sweep_cpu.json`):\n\n"
            + d["gathered_md"].strip() + "\n")


def hw_runner() -> str:
    d = _load("hw_cpu.json")
    c, r, st = d["codec"], d["round_trip"], d["stream"]
    rows = [
        ["encode POSITION packets [packets/s]", f"{c['encode_packets_per_s']:,} (table CRC-8 from the `crc` library + `cobs`)",
         f"{c['peer_encode_packets_per_s']:,} (`crc.Calculator.checksum` per packet + `cobs`)", f"{c['encode_ratio']}×"],
        ["decode stream, MTU-sized chunks [packets/s]", f"{c['decode_packets_per_s']:,} (`PacketReader.feed`)",
         f"{c['peer_decode_packets_per_s']:,} (split + `cobs.decode` + `Calculator.checksum`)", f"{c['decode_ratio']}×"],
        ["REQUEST POSITION+VELOCITY → 14 answers (14 datagrams, one packet each), simulator in its own process "
         "(`uvms-hw sim`), UDP loopback", f"p50 {r['bravo7_sim_process']['p50_ms']} ms, p99 {r['bravo7_sim_process']['p99_ms']} ms",
         f"bare UDP echo thread: p50 {r['peer_udp_echo']['p50_ms']} ms, p99 {r['peer_udp_echo']['p99_ms']} ms",
         f"{r['p50_ratio']}× (p50)"],
        ["same, simulator as a thread of the client process (as `uvms-hw run --sim`)",
         f"p50 {r['bravo7_sim_thread']['p50_ms']} ms, p99 {r['bravo7_sim_thread']['p99_ms']} ms", "", ""],
        [f"state stream at {st['stream_hz']} Hz from `uvms-hw sim` (heartbeat, `Bravo7.stream_state`)",
         f"{st['streamed']['states_per_s']} states/s, {st['streamed']['packets_sent_per_state']} packets sent per state",
         f"polling (`read_state`) as fast as it goes: {st['polled']['states_per_s']} states/s, "
         f"{st['polled']['packets_sent_per_state']} request per state", ""],
    ]
    return (f"`{d['command']}` ({d['device']}; `benchmarks/results/hw_cpu.json`):\n\n"
            + md_table(["what", "project", "peer", "ratio"], rows) + "\n")


def hw_acceptance() -> str:
    d = _load("hw_acceptance_cpu.json")

    def run(r):
        res, sim = r["result"], r["result"].get("sim") or {}
        return (f"{res['status']}, {res['gates']} gates, max gate error {res['max_gate_error_rad']:.5f} rad / "
                f"{res['max_gate_error_mm']:.2f} mm, {res['duration_s']:.1f} s, {res['rejected_states']} rejected states"
                + (f", {sim['dropped']} datagrams dropped and {sim['corrupted']} corrupted by the simulator, "
                   f"{res['link_timeouts']} tick timeouts, {sim['limit_violations']} demands outside the limits"
                   if sim.get("dropped") else ""))
    clean, lossy = d["runs"]
    return (f"`{clean['command']}` and `{lossy['command']}` (real time, the two runs side by side on the 2-core CPU; "
            f"`benchmarks/results/hw_acceptance_cpu.json`): {run(clean)}; with loss and corruption: {run(lossy)}.\n")


def sched_benchmark() -> str:
    d = _load("sched_cpu.json")
    t, sc, lg = d["thesis_instance"], d["scoring"], d["large"]
    rows = [["greedy (\"Dijkstra\")", f"{t['greedy']['cost']:.4f} (`{t['greedy']['path']}`)", f"{t['greedy']['median_ms']:.3g}",
             f"{t['greedy']['thesis_ms']}"],
            ["GRASP, 1000 iterations, one jitted call", f"{t['grasp_1000']['cost']:.4f} (optimum in "
             f"{t['grasp_1000']['optimum_found_fraction']:.0%} of the runs)", f"{t['grasp_1000']['median_ms']:.3g}",
             f"{t['grasp_1000']['thesis_ms']}"],
            ["A* (thesis heuristic)", f"{t['astar']['cost']:.4f}", f"{t['astar']['median_ms']:.3g}", f"{t['astar']['thesis_ms']}"],
            ["exact DP", f"{t['exact']['cost']:.4f}", f"{t['exact']['median_ms']:.3g}", "—"],
            ["OR-Tools, first solution", f"{t['ortools_first_solution']['cost']:.4f}",
             f"{t['ortools_first_solution']['time_ms']:.3g}", "—"],
            ["OR-Tools, guided local search 1 s", f"{t['ortools_gls_1s']['cost']:.4f}", f"{t['ortools_gls_1s']['time_ms']:.4g}", "—"]]
    big = []
    for key, label in (("10x10_1to3_bases", "1–3 allowed bases per object"), ("10x10_all_bases", "every base allowed")):
        g = lg[key]

        def ort(name):
            return f"{g[name]['time_ms']:.4g} ms, gap {g[name]['gap']:.1%}"
        big.append([label, f"{g['exact']['median_ms']:.3g} ms ({g['exact']['states']:,} states)",
                    f"{g['grasp_1000']['median_ms']:.3g} ms, {g['grasp_1000']['gap_mean']:.1%} / {g['grasp_1000']['gap_best']:.1%}",
                    ort("ortools_first_solution"), ort("ortools_gls_1s"), ort("ortools_gls_5s")])
    return (f"`{d['command']}` ({d['device']}; `benchmarks/results/sched_cpu.json`; medians over repeats after a "
            f"warm-up, GRASP's one-off compile of {t['grasp_compile_s']:.1f} s excluded).\n\n"
            "Thesis instance (eq. 4.1, 10 nodes):\n\n"
            + md_table(["solver", "cost", "time [ms]", "thesis (Table 5.5) [ms]"], rows)
            + f"\n\nBatch scoring (`score`, {sc['batch']:,} schedules of 13 nodes, about half of them shuffled and "
            f"invalid): {_sci(sc['schedules_per_s'])} schedules/s (best run {_sci(sc['schedules_per_s_best'])}); the "
            f"same checks in NumPy: {_sci(sc['peer_numpy_schedules_per_s'])}/s "
            f"({sc['schedules_per_s'] / sc['peer_numpy_schedules_per_s']:.1f}×).\n\n"
            "10 objects / 10 bases (random costs; gaps to the exact optimum):\n\n"
            + md_table(["instance", "exact DP", "GRASP 1000 it (gap mean / best of 5)", "OR-Tools first solution",
                      "OR-Tools GLS 1 s", "OR-Tools GLS 5 s"], big) + "\n")


def test_suite() -> str:
    """CI's run in a fresh clone (``benchmarks/test_suite.py``): setup, the fast suite, the slow one."""
    d = _load("test_suite_cpu.json")
    t = d["targets"]
    fast, slow = t["test"], t["test-slow"]
    return (f"On the {d['cpu_count']}-core machine, from a fresh clone of commit {d['commit'][:7]} "
            f"(`{d['command']}`, `benchmarks/results/test_suite_cpu.json`): `make setup` {_minutes(t['setup']['seconds'])}, "
            f"then the {fast['passed']} fast tests {_minutes(fast['seconds'])} and the {slow['passed']} slow ones "
            f"{_minutes(slow['seconds'])} ({slow.get('skipped', 0)} skipped: GPU only), compiling everything; load "
            f"average {d['load_average_start'][0]:.1f} at the start.\n")


def test_suite_isa() -> str:
    """The fast suite with XLA's CPU code held to an older instruction set (``--isa``)."""
    d = _load("test_suite_avx_cpu.json")
    t = d["targets"]["test"]
    failed = f", {t['failed']} failed" if t.get("failed") else ""
    return (f"With XLA's CPU code generation held to AVX (`XLA_FLAGS={d['xla_flags']}`; `{d['command']}`, "
            f"`benchmarks/results/test_suite_avx_cpu.json`), from a fresh clone of commit {d['commit'][:7]}: the "
            f"{t['passed']} fast tests passed{failed} in {_minutes(t['seconds'])}, as with XLA's default code path.\n")


def cold_demo() -> str:
    d = _load("cold_demo_cpu.json")
    w, o = d["whole_run"], d["outcome"]
    stages = ", ".join(f"{name} {sec:.0f} s" for name, sec in o["stage_seconds"].items())
    return (f"A newcomer's first run, with an empty compilation cache (`{d['command']}`, {d['cpus']} CPU cores): "
            f"pipeline {w['wall_s']:.1f} s, of which {w['compile_s']:.1f} s compiling {w['programs_compiled']} XLA "
            f"programs ({stages}); the same docked pose, {o['planned']['RRTConnect_success']} edges planned, hw "
            f"{o['hw']['reason']}.\n"
            + _fresh_demo())


def _fresh_demo() -> str:
    f = _load("fresh_demo_cpu.json")
    kernels = ("the planner's Numba kernels compiled too, from an empty Numba cache: a machine's first run"
               if not f.get("numba_kernels_cached_before") else
               "the planner's Numba kernels loaded from this machine's cache of the same source")
    return (f"\n`make demo` from a fresh clone (`{f['command']}`: clone, virtual environment and install from pip's cache, "
            f"then the demo with an empty compilation cache): {f['total_s']:.1f} s, of which {f['setup_s']:.1f} s setup and "
            f"{f['pipeline_s']:.1f} s pipeline ({kernels}; plan stage {f['stage_seconds']['plan']:.0f} s).\n")