"""Report blocks of the hovering vehicle: MJX batch, robustness, trim, levelling."""

from __future__ import annotations

from uvms_jax.text import md_table
from blocks._format import RESULTS, _load, _rate

__all__ = ["hover_mjx", "hover_robustness", "hover_vehicle", "hover_levelling", "hover_controllers", "hover_bpl"]


def hover_mjx() -> str:
    rows = []
    for name in ("hover_mjx_cpu.json", "hover_mjx_h100.json"):
        d = _load(name)
        where = "2-core CPU" if d["device"]["platform"] == "cpu" else d["device"]["device_kind"]
        cpu = d["cpu_mujoco_hoversim"]["steps_per_s"]
        for r in d["mjx"]:
            rows.append([where, str(r["batch"]), f"{r['compile_s']:.1f}", f"{r['run_s']:.3f}", _rate(r["env_steps_per_s"]),
                         _rate(r["scenarios_per_s"]), f"{r['env_steps_per_s'] / cpu:.0f}×"])
    gpu, cpu_file = _load("hover_mjx_h100.json"), _load("hover_mjx_cpu.json")
    return (f"`{cpu_file['command']}` (2-core CPU, jax {cpu_file['versions']['jax']}) and `{gpu['command']}` "
            f"({gpu['device']['device_kind']}, jax {gpu['versions']['jax']}); {gpu['physics_steps_per_scenario']} "
            f"physics steps of {gpu['model']['physics_dt_s'] * 1e3:g} ms per scenario on the GPU "
            f"({gpu['simulated_s']:g} s simulated), float32. CPU MuJoCo (`HoverSim`, one thread, the same model and "
            f"motion): {_rate(cpu_file['cpu_mujoco_hoversim']['steps_per_s'])} steps/s here, "
            f"{_rate(gpu['cpu_mujoco_hoversim']['steps_per_s'])} on the GPU machine's CPU (MuJoCo's C step alone, "
            f"without our buoyancy and control: {_rate(cpu_file['cpu_mujoco_mj_step_only']['steps_per_s'])} and "
            f"{_rate(gpu['cpu_mujoco_mj_step_only']['steps_per_s'])}); the last column is the batch against `HoverSim` "
            "on the same machine.\n\n"
            + md_table(["device", "scenarios", "compile [s]", "run [s]", "env-steps/s", "scenarios/s", "vs CPU MuJoCo"],
                     rows) + "\n")


def _mm(v: float) -> str:
    return f"{1e3 * v:.1f}" if v < 0.1 else f"{1e3 * v:.0f}"


def hover_robustness() -> str:
    """Gate tool error against current speed per controller (docs/hover.md), from
    ``benchmarks/hover_robustness.py``'s full-size GPU run, and its whole-plan and throughput
    runs."""
    d = _load("hover_robustness_curve_h200.json")
    variants = d["variants"]
    rows = [[f"{r['speed_m_s']:.1f}"] + [f"{_mm(v['per_speed'][i]['worst_gate_tool_error_m'])} / "
                                         f"{_mm(v['per_speed'][i]['p95_gate_tool_error_m'])}" for v in variants]
            for i, r in enumerate(variants[0]["per_speed"])]
    top = f"{max(d['speeds_m_s']):g}"
    rows.append(["first loses 10 mm"] + [f"{v['first_speed_losing_10mm_m_s']:g} m/s"
                                         if v["first_speed_losing_10mm_m_s"] is not None else f"not up to {top} m/s"
                                         for v in variants])
    thrust_bad = sum(r["thrust_violations"] for v in variants for r in v["per_speed"])
    past = [r for v in variants for r in v["per_speed"] if r["joint_violations"]]
    joints = ("no joint past a limit" if not past else
              f"joints past a limit only from {min(r['speed_m_s'] for r in past):g} m/s, beyond the thrusters, by up to "
              f"{max(r['max_joint_excess_rad'] for r in past):.3f} rad (the MJX model has no joint stops; the "
              "controller's targets stay within the limits)")
    n = d["navigation"]
    size = d["reduction"] or "the full size: 48 directions, the whole plan, the three controllers"
    text = (f"`{d['command']}` (the demo's plan at its docked pose; {d['device']}, jax {d['jax']}, {d['dtype']}): "
            f"{size}. {d['scenarios']} scenarios (3 controllers × exact or noisy navigation × "
            f"{len(d['speeds_m_s'])} speeds × {d['directions']} directions), {d['simulated_s']:.0f} s and {d['gates']} "
            f"gates each, in one MJX call ({d['compile_s']:.0f} s compile, {d['run_s']:.0f} s run, "
            f"{_rate(d['env_steps_per_s'])} env-steps/s). Navigation noise: fixes at {n['rate_hz']:g} Hz, "
            f"{1e3 * n['latency_s']:.0f} ms late, {1e3 * n['position_noise_m']:g} mm and {n['angle_noise_deg']:g}°. "
            f"Each cell: the largest gate tool error of a scenario, worst / 95th percentile over the directions [mm]; "
            f"{thrust_bad} periods with a thrust past its limit; {joints}.\n\n"
            + md_table(["current [m/s]"] + [v["name"] for v in variants], rows) + "\n")
    for name, where in (("hover_robustness_whole_body_h200.json", None), ("hover_robustness_h200.json", None)):
        if (RESULTS / name).exists():
            text += _whole_plan(_load(name), where)
    if (RESULTS / "hover_robustness_throughput_h200.json").exists():
        g = _load("hover_robustness_throughput_h200.json")
        text += (f"\nThroughput on the {g['device']} (`{g['command']}`, jax {g['jax']}, {g['dtype']}; "
                 f"{g['reduction']}): {g['scenarios']} scenarios in one call, {_rate(g['env_steps_per_s'])} "
                 f"env-steps/s with the controller in the loop ({g['compile_s']:.0f} s compile, {g['run_s']:.0f} s run).\n")
    return text


def _whole_plan(w: dict, where: str | None) -> str:
    """One sentence: the whole plan's worst-direction gate tool error per speed, exact / noisy
    navigation, with the gates reached, the runs held (the current beyond the thrusters) and the
    limit violations."""
    exact = next(x for x in w["variants"] if not x["navigation_noise"])["per_speed"]
    noisy = next(x for x in w["variants"] if x["navigation_noise"])["per_speed"]
    cells = "; ".join(f"{a['speed_m_s']:g} m/s: {_mm(a['worst_gate_tool_error_m'])} / {_mm(b['worst_gate_tool_error_m'])}"
                      f" (gates reached in the worst direction {a['gates_reached_worst']:.2f} / "
                      f"{b['gates_reached_worst']:.2f}; held {a.get('held', 0)} / {b.get('held', 0)} of {a['scenarios']})"
                      for a, b in zip(exact, noisy))
    thrust = sum(r["thrust_violations"] for r in exact + noisy)
    joints = sum(r["joint_violations"] for r in exact + noisy)
    size = (f"{w['scenarios']} scenarios ({w['repetitions']} draws of navigation noise per direction) in one call at "
            f"{_rate(w['env_steps_per_s'])} env-steps/s, " if w.get("repetitions", 1) > 1 else "")
    return (f"\nThe whole plan ({w['gates']} gates, {w['simulated_s']:.0f} s), whole-body controller, "
            f"{w['directions']} directions, {size}on the {where or w['device']} (`{w['command']}`, jax {w['jax']}): "
            f"worst-direction gate tool error, exact / noisy navigation [mm]: {cells}; {thrust} thrust and {joints} "
            "joint-limit violations (held: the thrusters saturated, the reason in the run).\n")


def hover_vehicle() -> str:
    """The hovering vehicle's derived figures (docs/hover.md), from ``benchmarks/hover_vehicle.py``."""
    d = _load("hover_vehicle.json")
    e, v, p = d["largest_effort"], d["steady_speed_m_s"], d["poles_rad_s"]

    def poles(roots):
        out = []
        for re_, im in roots:
            if im < 0:
                continue
            out.append(f"{re_:.2g} ± {im:.2g}j" if im > 0 else f"{re_:.2g}")
        return ", ".join(out).replace("-", "−")

    limits = sorted(set(d["thrust_limit_n"]))
    return (f"`{d['command']}` (`benchmarks/results/hover_vehicle.json`):\n\n"
            + md_table(["figure", "value"], [
                ["thrust configuration matrix", f"rank {d['thrust_matrix_rank']}, {d['thrusters']} thrusters of "
                                                f"±{'/'.join(f'{x:g}' for x in limits)} N"],
                ["largest pure effort", f"surge {e['surge']:.0f} N, sway {e['sway']:.0f} N, heave {e['heave']:.0f} N, "
                                        f"yaw {e['yaw']:.0f} N·m"],
                ["steady speed at that effort against the hull's own drag",
                 f"surge {v['surge']:.2f} m/s, sway {v['sway']:.2f} m/s, heave {v['heave']:.2f} m/s"],
                ["hydrostatic restoring moment of the hull", f"{d['restoring_moment_nm_per_rad']:.0f} N·m per radian of roll or pitch"],
                [f"rigid vehicle, the {d['arm'].replace('bravo7', 'Bravo 7')} held at mid-range",
                 f"{d['mass_kg']:.1f} kg, {d['yaw_inertia_kg_m2']:.1f} kg·m² about z"],
                ["station-keeping poles, no drag", f"{poles(p['translation'])} rad/s in each translation; "
                                                   f"{poles(p['yaw'])} rad/s in yaw"]]) + "\n")


def hover_levelling() -> str:
    """The demo's hover stage: the largest tilt with levelling on (docs/hover.md)."""
    runs = _load("demo_cpu.json")["hover"]["runs"]
    tilt = max(r["max_tilt_deg"] for r in runs.values())
    return (f"Held level by the vertical thrusters, the tilt stays within {tilt:.1f}° in each of the demo's "
            f"{len(runs)} hover runs (the `hover` stage of `benchmarks/results/demo_cpu.json`).\n")


def _controllers_row(d: dict, control: str, speed: str) -> str:
    runs = [r for r in d["runs"] if r["control"] == control and f"{r['speed_m_s']:.1f}" == speed]
    reached = min(r["gates_reached"] for r in runs)
    return (f"{1e3 * d['worst_tool_error_m'][control][speed]:.1f} / {1e3 * d['worst_gate_tool_error_m'][control][speed]:.1f}"
            f" mm, {reached}/{runs[0]['gates']}")


def hover_controllers() -> str:
    plain, ff, nav, gust = (_load(f"hover_controllers{k}_cpu.json") for k in ("", "_ff", "_nav", "_gust"))
    directions = sorted({r["direction_deg"] for r in plain["runs"]})
    columns = [("PID (replay)", plain, "pid"), ("+ feed-forward", ff, "feed_forward"), ("whole-body", plain, "whole_body"),
               ("whole-body, navigation fixes", nav, "whole_body")]
    rows = [[f"{float(s):g} m/s" if float(s) else "still water", *(_controllers_row(d, c, s) for _, d, c in columns)]
            for s in plain["worst_tool_error_m"]["pid"]]
    n = nav["navigation"]
    g = {c: {s: 1e3 * v for s, v in gust["worst_gate_tool_error_m"][c].items()} for c in ("pid", "whole_body")}
    return (f"`{plain['command']}` and its variants (`--controls feed_forward`, `--navigation`), the demo's plan and docked "
            f"pose, {plain['simulated_s']:.0f} s simulated, currents from {len(directions)} directions "
            f"({', '.join(f'{x:g}°' for x in directions)}); worst tool error over the run / worst at a gate, and the "
            f"fewest gates reached (a gate: the tool within 10 mm; the whole-body controller's also within 2°):\n\n"
            + md_table(["current", *(c for c, _, _ in columns)], rows) +
            f"\n\nNavigation fixes at {n['rate_hz']:g} Hz, {1e3 * n['latency_s']:.0f} ms late, {1e3 * n['position_noise_m']:g} mm "
            f"and {n['angle_noise_deg']:g}° of noise, fused with dead reckoning (gain {n['fix_gain']:g}). With gusts "
            f"({gust['gust_m_s']:g} m/s, `{gust['command']}`) the worst gate error is {g['pid']['0.3']:.0f} mm (PID) against "
            f"{g['whole_body']['0.3']:.1f} mm (whole-body) at 0.3 m/s; at 0.5 m/s the gusts exceed the thrusters and both "
            f"lose the path ({g['pid']['0.5']:.0f} / {g['whole_body']['0.5']:.0f} mm).\n")


def _bpl_cell(d: dict, control: str, speed: float) -> str:
    r = next(r for r in d["runs"] if r["control"] == control and r["speed_m_s"] == speed)
    return (f"{1e3 * r['max_gate_tool_error_m']:.1f} / {1e3 * r['mean_gate_tool_error_m']:.1f} mm, "
            f"{1e3 * r['max_tool_error_m']:.1f} mm; {r['gates_tool_within_tolerance']}/{r['gates']}"
            + ("" if r["status"] == "completed" else f", {r['status']}"))


def hover_bpl() -> str:
    """The whole-body controller on the CPU simulator against the same controller in the BPL
    executor's loop on the simulated arm (docs/hover.md, "Over BPL")."""
    exact, nav = _load("hover_bpl_cpu.json"), _load("hover_bpl_nav_cpu.json")
    speeds = sorted({r["speed_m_s"] for r in exact["runs"]})
    columns = [("CPU simulator", exact, "whole_body"), ("over BPL", exact, "whole_body_bpl"),
               ("CPU simulator, navigation fixes", nav, "whole_body"), ("over BPL, navigation fixes", nav, "whole_body_bpl")]
    rows = [[f"{s:g} m/s" if s else "still water", *(_bpl_cell(d, c, s) for _, d, c in columns)] for s in speeds]
    return (f"`{exact['command']}` (and `--navigation`), the demo's plan and docked pose; the tool's error at the "
            "gates, worst / mean, its worst over the run (over BPL: from its path), and the gates with the tool within "
            "10 mm (the CPU simulator's gates are the plan's segments; the executor's are its waypoints and gripper "
            "steps):\n\n" + md_table(["current", *(c for c, _, _ in columns)], rows) + "\n")
