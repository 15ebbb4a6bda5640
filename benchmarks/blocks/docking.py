"""Report blocks of docking: search, certificate, fitness kernels, GA, panel, map route, collision."""

from __future__ import annotations

import math

from uvms_jax.text import md_table
from blocks._format import HOPPER_FP32, RESULTS, _int, _load, _range, _rate, _reproduction, _sci

__all__ = ["docking_search", "docking_certify", "docking_fitness", "docking_ga", "docking_panel", "docking_map", "docking_collision"]


def docking_search() -> str:
    ref_file = "docking_reference_demo_h100.json"
    ref, d = _load(ref_file)["reference"], _load("docking_search_demo_cpu.json")
    s = d["search"]
    runs = s["runs"]
    g = ref["grid"]
    rows = [[str(r["seed"]), f"{r['best']:.4f}", f"{r['ratio']:.4f}", f"{r['ga_best']:.3f}", f"{r['coarse_grid_best']:.3f}",
             f"{r['grid_zoom_best']:.4f}", str(r["evaluations"]), f"{r['wall_s']:.0f}"] for r in runs]
    first, last = runs[0]["seed"], runs[-1]["seed"]
    return (f"Dense reference on an **{_load(ref_file)['device_kind']}** (`python benchmarks/docking_search.py "
            f"--reference`):\na {' × '.join(map(str, g['counts']))} grid ({ref['grid_candidates']:,} poses, "
            f"{ref['grid_seconds']:.1f} s) reaching {ref['grid_fitness']:.4f}, then {g['refine_stages']} zoom stages of "
            f"{g['refine_counts'][0]}^4 ({ref['zoom_seconds']:.1f} s): **{ref['fitness']:.4f}**.\n\n"
            f"The demo's docking stage on the **2-core CPU** ({d['machine']}, jax {d['jax']}), seeds {first}–{last}\n"
            f"(`python benchmarks/docking_search.py --seeds {first} {len(runs)} --reference-file "
            f"benchmarks/results/{ref_file}`): **{s['reached_0.99']} of {len(runs)}** reach ≥ 0.99 of the reference "
            f"(ratio {s['ratio_min']:.4f} at worst, median {s['ratio_median']:.4f}), each with "
            f"{min(r['evaluations'] for r in runs):,}–{max(r['evaluations'] for r in runs):,} evaluations in "
            f"{s['wall_s_median']:.0f} s (median, compilation cache warm).\n\n"
            + md_table(["seed", "best", "best / reference", "GA runs' best", "lattice's best", "after zoom",
                      "evaluations", "wall [s]"], rows)
            + "".join(f"\n\nSeed {r['seed']} misses: its lattice's best scores {r['coarse_grid_best']:.3f} and its GA runs' "
                      f"{r['ga_best']:.3f} (eq. 15 is −b·D where a target is out of reach): no start lies in the optimum's "
                      f"basin, and the zoom stages climb only to {r['best']:.3f}."
                      for r in runs if r["ratio"] < 0.99) + "\n")


def docking_certify() -> str:
    """A certified docking run of the demo's fitness on a GPU (docs/docking.md), from its
    ``summary.json`` kept as ``docking_certify_demo_h100.json``."""
    d = _load("docking_certify_demo_h100.json")
    s, c = d["summary"], d["summary"]["certificate"]
    ref = c["reference"]
    ratios = [f / ref["fitness"] for f in s["ga_fitness"]]
    return (f"On an {d['device']} (jax {d['jax']}; `benchmarks/results/docking_certify_demo_h100.json`): the reference "
            f"{ref['fitness']:.4f} ({ref['search']}, {_int(ref['evaluations'])} poses, the grid at "
            f"{_int(s['grid_candidates_per_s'])} poses/s), and {len(ratios)} GA runs at "
            f"{_int(s['ga_evaluations_per_s'])} evaluations/s whose bests reach {_range(ratios)} of it "
            f"({sum(r >= c['accept_ratio'] for r in ratios)} of {len(ratios)} ≥ {c['accept_ratio']:g}): "
            f"`ga_certified: {str(c['ga_certified']).lower()}` (best {c['ga_best_ratio']:.4f}).\n")


#: benchmarks/docking_fitness.py's variants, as the tables name them.
FITNESS_VARIANTS = {"kernels": "IK kernel + collision kernel (the library's GPU path)",
                    "ik kernel": "IK kernel, XLA collision test", "cholesky": "XLA, written-out Cholesky (the library's CPU path)",
                    "lu": "XLA, LU solve"}


def docking_fitness() -> str:
    """The demo's docking fitness per batch and variant (``benchmarks/docking_fitness.py``: each
    file's variants timed in one process), and the GPU path's arithmetic against the H100's
    compute ceiling."""
    names = ("docking_fitness_cpu.json", "docking_fitness_h100.json")
    rows = []
    for name in names:
        d = _load(name)
        device = d["device"] if d["platform"] == "gpu" else f"{d['cpus']}-core CPU"
        for variant, runs in d["variants"].items():
            rows += [[device, _int(r["batch"]), FITNESS_VARIANTS[variant], _sci(r["poses_per_s"]), f"{r['compile_s']:.0f}",
                      f"{r['fitness_sum']:.9g}"] for r in runs]
    cpu, gpu = (_load(n) for n in names)
    kernels, ik = gpu["variants"]["kernels"][-1], gpu["variants"]["ik kernel"][-1]
    chol, lu = cpu["variants"]["cholesky"][-1], cpu["variants"]["lu"][-1]
    flops = kernels["dls_flops_per_pose"] + gpu["collision_flops_per_pose"]
    ceiling = 2 * HOPPER_FP32  # XLA counts a multiply-add as two flops
    return (" and ".join(f"`{_load(n)['command']}`" for n in names) + f" (jax {gpu['jax']} on the GPU). At "
            f"{_int(kernels['batch'])} poses on the {gpu['device']} the library's path runs "
            f"**{_sci(kernels['poses_per_s'])} poses/s**, {kernels['poses_per_s'] / ik['poses_per_s']:.2f}× the IK kernel "
            f"with XLA's collision test (the path before the collision kernel) in the same process, with the same "
            f"fitness sum. A pose costs {kernels['dls_flops_per_pose'] / 1e6:.2f} Mflop of DLS iterations and "
            f"{gpu['collision_flops_per_pose'] / 1e6:.2f} Mflop of collision tests (XLA's count of the same arithmetic "
            f"on the GPU), so the kernels achieve {flops * kernels['poses_per_s'] / 1e12:.1f} TFLOP/s: "
            f"{100 * flops * kernels['poses_per_s'] / ceiling:.0f} % of the H100's {ceiling / 1e12:.0f} TFLOP/s FP32 ceiling "
            f"(132 SMs × 128 lanes × 1.98 GHz, a multiply-add as two flops), which bounds the fitness near "
            f"{_sci(ceiling / flops)} poses/s. On the CPU at {_int(chol['batch'])} poses the written-out Cholesky runs "
            f"{chol['poses_per_s'] / lu['poses_per_s']:.2f}× the LU solve.\n\n"
            + md_table(["device", "batch", "variant", "poses/s", "compile [s]", "fitness sum"], rows) + "\n\n"
            + "\n".join(_fitness_stages(_load(n)) for n in names))


def _fitness_stages(d: dict) -> str:
    """Where the fitness's time goes (``stages`` of a docking_fitness record), one paragraph."""
    st = d["stages"]["seconds"]
    ik, fk, hit, whole = st["ik"], st["ik + fk + reach test"], st["ik + fk + collision test"], st["fitness"]
    device = d["device"] if d["platform"] == "gpu" else f"{d['cpus']}-core CPU"
    return (f"Where the time goes, {device} at {_int(d['stages']['batch'])} poses (each piece compiled alone, "
            f"the library's path): the IK {1e3 * ik:.1f} ms ({1e3 * st['ik, 1 iteration']:.1f} ms with one "
            f"iteration), with the forward kinematics and reach test {1e3 * fk:.1f} ms, with the collision test "
            f"instead {1e3 * hit:.1f} ms, with w instead {1e3 * st['ik + w']:.1f} ms; the whole fitness "
            f"{1e3 * whole:.1f} ms: the IK {100 * ik / whole:.0f} %, the collision test {100 * (hit - fk) / whole:.0f} %.\n")


def docking_ga() -> str:
    """The paper's docking problem: the GA batch, the dense grid and CMA-ES (evosax) on the CPU and
    on a GPU, from ``benchmarks/docking.py``'s result files."""
    files = ("docking_cpu.json", "docking_h100.json")
    cpu, *gpus = (_load(f) for f in files)

    def ga_row(d):
        g = d["ga"]
        return (f"GA, {g['runs']} run{'s' * (g['runs'] > 1)} × {_int(g['population'])} in one call "
                f"({_range(g['generations'], 'd')} generations; {_int(sum(g['evaluations']))} evaluations"
                + (f", fitness cache of {g['eval_chunk']}" if g["eval_chunk"] else ", no cache") + ")")

    def t(part):
        return f"{part['best_s']:.3g} s ({part['median_s']:.3g} s)" if "median_s" in part else f"{part['best_s']:.3g} s"

    def grid_row(d):
        g = d["grid"]
        return (f"grid search, {_int(g['candidates'])} candidates ({' × '.join(map(str, g['counts']))}), "
                f"chunks of {_int(g['chunk'])}")

    def cma_row(d):
        c = d["cmaes"]
        return f"CMA-ES (evosax), {c['runs']} runs × {_int(c['population'])} × {c['generations']} generations"

    rows = []
    for d in (cpu, *gpus):
        label = "2-core CPU" if d is cpu else d["device_kind"]
        g, gr, c = d["ga"], d["grid"], d["cmaes"]
        rows += [[label, ga_row(d), t(g), f"{_rate(g['evaluations_per_s'])} evaluations/s", f"{g['compile_and_first_s']:.0f} s"],
                 [label, grid_row(d), t(gr), f"{_rate(gr['candidates_per_s'])} candidates/s",
                  f"{gr['compile_and_tiny_grid_s']:.0f} s"],
                 [label, cma_row(d), t(c), f"{_rate(c['evaluations_per_s'])} evaluations/s", f"{c['compile_and_first_s']:.0f} s"]]
    # The optimum of the paper's problem: the grid of `make papers` (docs/reproduction.json), finer
    # than the CPU's grid, which the GA runs beat.
    optimum = _reproduction()["sections"]["docking"]["grid_best"]
    ratios = [f / optimum for f in cpu["ga"]["best_fitness"]]
    on = lambda parts: " and ".join(parts)  # noqa: E731
    return (f"Commands: `{cpu['command']}` (2-core {cpu['platform']} CPU, jax {cpu['jax']}, load average "
            f"{cpu['load_average_start'][0]:.1f} at the start) and "
            + on(f"`{d['command']}` ({d['device_kind']}, jax {d['jax']})" for d in gpus)
            + "; files " + ", ".join(f"`benchmarks/results/{f}`" for f in files) + ". Times after compilation, best "
            "of the repeats (median in brackets).\n\n"
            + md_table(["device", "what", "time", "rate", "compile + first call"], rows)
            + f"\n\nGA against CMA-ES, evaluations/s: {cpu['ga_over_cmaes_evaluations_per_s']:.2f}× on the CPU, "
            + on(f"{d['ga_over_cmaes_evaluations_per_s']:.2f}× on the {d['device_kind']}" for d in gpus)
            + f". On the CPU the {cpu['ga']['runs']} GA runs reach "
              f"{_range(ratios, '.3f')} of the optimum {optimum:.4f} (the grid of `make papers`, docs/reproduction.json; "
              f"{sum(r >= 0.99 for r in ratios)} of {len(ratios)} ≥ 0.99); the "
              f"{_int(cpu['grid']['candidates'])}-candidate grid above finds {cpu['grid']['best_fitness']:.4f}, "
              f"CMA-ES {max(cpu['cmaes']['best_fitness']):.4f}. The paper's 1e8-candidate grid takes "
            + on(f"{d['grid']['best_s']:.2f} s on the {d['device_kind']}" for d in gpus) + ". " + _grid_chunks())


def _grid_chunks() -> str:
    """The paper's 1e8 grid in chunks of several sizes on a GPU: compile time and search time."""
    d = _load("docking_grid_chunks_h100.json")
    runs = [(_int(r["chunk"]), r["grid"]["compile_and_tiny_grid_s"], r["grid"]["best_s"]) for r in d["runs"]]
    return (f"In chunks of {', '.join(c for c, _, _ in runs[:-1])} and {runs[-1][0]} candidates it compiles (with a "
            f"2⁴ grid's call) in {', '.join(f'{t:.0f}' for _, t, _ in runs)} s and searches the grid in "
            f"{', '.join(f'{t:.2f}' for _, _, t in runs)} s on the {d['device_kind']} (`{d['command']}`, "
            f"`benchmarks/results/docking_grid_chunks_h100.json`).\n")


def docking_panel() -> str:
    """The Bravo 7 docked beside a panel (numerical IK), from ``experiments/docking.py
    docking/preset=bravo7``'s outputs on a GPU."""
    d = _load("docking_panel_h100.json")
    s, g = d["summary"], d["grid_optimum"]
    b = d["best_pose"]
    p = b["pose"]
    w = [t["w"] for t in b["targets"] if t["reached"]]
    return (f"{d['device_kind']}, jax {d['jax']}, float32, `{d['command']}` (`benchmarks/results/docking_panel_h100.json`): "
            f"the 7 GA runs in one call {s['ga_batch_seconds']:.1f} s after compilation "
            f"({s['ga_compile_and_first_batch_seconds']:.0f} s with it), {_range(s['ga_generations'], 'd')} generations, "
            f"{_int(sum(s['ga_evaluations']))} evaluations, **{_int(s['ga_evaluations_per_s'])} evaluations/s**; the grid's "
            f"{_int(g['candidates'])} candidates ({' × '.join(map(str, g['counts']))}) {g['seconds']:.0f} s "
            f"({_int(s['grid_candidates_per_s'])} candidates/s), its {len(g['refined']['stages'])} zoom stages "
            f"({_int(g['refined']['candidates'])} candidates) {g['refined']['seconds']:.0f} s with their compilation.\n\n"
            + md_table(["reference", "fitness", "GA / reference, 7 runs", "runs ≥ 0.99"],
                     [[f"grid {' × '.join(map(str, g['counts']))}", f"{g['fitness']:.4f}",
                       ", ".join(f"{r:.3f}" for r in s["ga_ratio_to_grid"]), str(s["ga_runs_within_0.99_of_grid"])],
                      [f"grid + {len(g['refined']['stages'])} zoom stages", f"{g['refined']['fitness']:.4f}",
                       ", ".join(f"{r:.3f}" for r in s["ga_ratio_to_refined_grid"]),
                       str(s["ga_runs_within_0.99_of_refined_grid"])]])
            + f"\n\nThe chosen pose ({b['source']}), x = {p['x']:.3f} m, y = {p['y']:.3f} m, z = {p['z']:.3f} m, "
              f"ψ = {math.degrees(p['psi']):.1f}°, reaches {len(w)} of {len(b['targets'])} panel poses with w "
              f"{min(w):.4f}–{max(w):.4f} (M_a = {b['Ma']:.4f}).\n")


def docking_map() -> str:
    # The CPU run first, then any GPU's.
    files = sorted((f.name for f in RESULTS.glob("docking_map_*.json")), key=lambda n: (n != "docking_map_cpu.json", n))
    out, rows = [], []
    for name in files:
        d = _load(name)
        device = f"{d['cpu_count']}-core CPU" if d["platform"] == "cpu" else d["device"]
        sm = d["summary"]
        out.append(f"**{device}** (jax {d['jax']}; `{d['command']}`): in **{sm['met']} of {sm['seeds']}** seeds the map's "
                   f"route loses ≤ 2 % of the analytic search's optimum with ≥ 50× fewer analytic evaluations: loss "
                   f"{100 * sm['loss_max']:.2f} % at worst (median {100 * sm['loss_median']:.2f} %), evaluation ratio "
                   f"{sm['ratio_min']:.0f}× at least (median {sm['ratio_median']:.0f}×).")
        for r in d["runs"]:
            rows.append([device, str(r["seed"]), f"{r['analytic_best']:.4f}", str(r["analytic_evaluations"]),
                         f"{r['best_candidate_fitness']:.3f}", f"{r['map_route_fitness']:.4f}",
                         f"{r['ratio_to_reference']:.4f}", str(r["map_route_analytic_evaluations"]),
                         f"{100 * r['loss_of_optimum']:.2f} %", f"{r['evaluation_ratio']:.0f}×",
                         f"{r['amortised_ratio']:.1f}×", f"{r['analytic_wall_s']:.0f} / {r['map_route_wall_s']:.0f}"])
    d = _load(files[0])
    r0 = d["runs"][0]
    return ("\n\n".join(out) + f" The map: {r0['map_tool_poses']} tool poses, what "
            f"{r0['map_vehicle_pose_equivalents']:.0f} docking evaluations of this task cost; the amortised ratio counts "
            f"them in one run. Reference: {d['reference_fitness']:.4f} (dense grid + zoom, "
            f"`benchmarks/results/docking_reference_demo_h100.json`).\n\n"
            + md_table(["device", "seed", "analytic search: best", "its evaluations", "map: best candidate (analytic)",
                      "map route: refined (analytic)", "/ reference", "its analytic evaluations", "loss of optimum",
                      "evaluation ratio", "amortised ratio (map counted)", "wall [s] analytic / map route"], rows) + "\n")


def docking_collision() -> str:
    """docs/docking.md's one world: docking's JAX collision test against the planner's sphere
    checker and MuJoCo, its size and its cost beside the link capsules it replaced, per arm."""
    rows, cost = [], []
    for name, arm in (("docking_collision_demo_cpu.json", "Bravo 7"), ("docking_collision_panda_cpu.json", "Panda")):
        d = _load(name)
        a, w, b = d["agreement"], d["world"], d["batch"]
        rows.append([arm, f"`{d['command']}`", f"{a['configurations']:,}".replace(",", " "),
                     f"{100 * a['jax_free']:.1f} / {100 * a['spheres_free']:.1f} / {100 * a['mujoco_free']:.1f}",
                     f"{100 * a['agree_spheres']:.2f}", f"{100 * a['agree_mujoco']:.2f}",
                     f"{a['jax_collision_spheres_free']} / {a['jax_collision_mujoco_free']}",
                     f"{a['jax_free_spheres_collision'] + a['jax_free_mujoco_collision']}"])
        cost.append([arm, str(w["spheres_per_row"]), f"{w['sphere_pairs_per_row']:,}".replace(",", " "),
                     f"{b['poses']} × {b['tool_poses']} × {b['seeds']} = {b['configurations']:,}".replace(",", " "),
                     f"{d['capsules']['run_s']:.3f}", f"{d['spheres']['run_s']:.3f}",
                     f"{d['spheres_over_capsules_time']:.1f}×", f"{d['fitness']['run_s']:.2f}",
                     f"{d['host']['load_average'][0]:.1f}"])
    return (md_table(["arm", "command (2-core CPU)", "configurations", "free: JAX / spheres / MuJoCo [%]",
                    "agrees with spheres [%]", "agrees with MuJoCo [%]", "JAX collision where spheres / MuJoCo free",
                    "JAX free where either collides"], rows) + "\n\n"
            + md_table(["arm", "spheres per target", "sphere pairs per target", "batch (poses × tool poses × seeds)",
                      "capsules [s]", "world [s]", "world / capsules", "whole fitness call [s]",
                      "load average (shared CPU)"], cost) + "\n"
            + _mesh_cost(_load("docking_collision_demo_cpu.json"), _load("docking_collision_panda_cpu.json"))
            + _mjx(_load("docking_collision_demo_cpu.json")))


def _mesh_cost(bravo: dict, panda: dict) -> str:
    w, v = panda["world"], bravo["world"]
    return (f"\nThe Panda's mesh links make {w['spheres_per_row'] / v['spheres_per_row']:.0f} times the Bravo 7's "
            f"spheres and {w['sphere_pairs_per_row'] / v['sphere_pairs_per_row']:.0f} times its sphere pairs: its world "
            f"takes {100 * panda['fitness']['collision_share_of_time']:.0f} % of its fitness call.\n")


def _mjx(d: dict) -> str:
    """MJX collision of the Bravo 7's docked MuJoCo scene, when the run measured it."""
    if "mjx" not in d:
        return ""
    m = d["mjx"]
    per_config = (m["run_s"] / m["configurations"]) / (d["spheres"]["run_s"] / d["batch"]["configurations"])
    return (f"\nMJX collision of the same MuJoCo scene (one vehicle pose, the base fixed): {m['run_s']:.2f} s for "
            f"{m['configurations']} configurations after a {m['compile_s']:.0f} s compilation, {per_config:.0f} times "
            "the world's time per configuration on this CPU (and it would need the base as a moving body for docking).\n")
