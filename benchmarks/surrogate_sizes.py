"""How many hidden neurons FFBN-KCI needs at our paper-sized run's data size: the design loop's
test error per size, on the paper's Jacobian form (spatial, eq. 6) by default.

Prints one JSON object (``--out`` also rewrites it as a file after every size, so a run stopped
early keeps the sizes it finished). The datasets and the initialisations are the ones
``experiments/surrogate.py`` (paper sizes: 6000 training samples, ours, as the paper gives
none, and the paper's 1000 test samples) draws from the same seed: the KCI dataset from the
run key's second split, FFBN-KCI's key folded in at its place in the settings' network list. The loop is the paper's (Fig. 6a,
``surrogate.design_ffbn``): sizes 1, 2, … up to L_iter, stopping at the first network whose
maximum relative test error (eq. 21) is below E = 2 %. Where it stops before the paper's 25
units, or ``--max-hidden`` is below 25, the paper's size is trained on its own as well (a fresh
initialisation from the key of that size), so the record always holds the error at 25 units.

    python benchmarks/surrogate_sizes.py --device gpu > benchmarks/results/surrogate_ffbn_kci_sizes_gpu.json
    # a run stopped early, continued in coarser steps (its record keeps the sizes it had):
    python benchmarks/surrogate_sizes.py --device gpu --resume FILE --step 5 --out FILE

Usage: python benchmarks/surrogate_sizes.py [--device cpu|gpu] [--jacobian spatial|geometric]
                                            [--max-hidden N] [--n-train N] [--out FILE]
                                            [--resume FILE] [--step N]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

from uvms_jax.files import json_text, write_json

NETWORK = "ffbn_kci"


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--device", default="cpu", help="JAX platform: cpu, gpu/cuda (default cpu)")
    ap.add_argument("--jacobian", choices=("spatial", "geometric"), default="spatial",
                    help="Jacobian form of KCI (spatial: the dexterity paper's eq. 6)")
    ap.add_argument("--max-hidden", type=int, default=None, help="L_iter (default: the settings', 100)")
    ap.add_argument("--n-train", type=int, default=None,
                    help="training samples (default: configs/surrogate.yaml's, 6000; the paper gives none)")
    ap.add_argument("--out", type=Path, default=None, help="also write the record here after every size")
    ap.add_argument("--resume", type=Path, default=None,
                    help="a record of an earlier run (same settings) to continue after its largest size")
    ap.add_argument("--step", type=int, default=None, help="size step of the loop (default: the settings', 1)")
    return ap


def _resume(record: dict, earlier: dict, args, step: int, k_loop, device_kind: str) -> tuple:
    """Continue ``earlier``'s record (a SystemExit if its settings differ): its steps, command
    and parts go into ``record``; returns the first size to try and the loop's key there."""
    import jax

    same = ("jacobian", "n_train", "n_test", "error_goal", "trainer", "target_mse", "max_epochs")
    if any(earlier[k] != record[k] for k in same):
        raise SystemExit(f"--resume {args.resume}: its settings differ from this run's in "
                         f"{[k for k in same if earlier[k] != record[k]]}")
    # Which sizes each part of the loop tried, and in what steps, stays in the record.
    record["steps"], record["command"] = earlier["steps"], earlier["command"] + " ; " + record["command"]
    record["parts"] = earlier.get("parts", [{"from": 1, "step": earlier.get("hidden_step", 1),
                                             "device": earlier["device"]}])
    start = earlier["largest_size_tried"] + step
    # The step-1 loop's key of size `start` (design_ffbn splits its key once per size).
    for _ in range(start - 1):
        k_loop, _ = jax.random.split(k_loop)
    record["parts"].append({"from": start, "step": step, "device": device_kind})
    return start, k_loop


def main() -> None:
    args = _parser().parse_args()
    os.environ["JAX_PLATFORMS"] = {"gpu": "cuda"}.get(args.device, args.device)

    import logging

    import jax

    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s", stream=sys.stderr)
    logging.getLogger("jax").setLevel(logging.WARNING)
    jax.config.update("jax_enable_x64", True)  # float64 datasets and LM training, as the design run

    from uvms_jax import kin, surrogate
    from uvms_jax.papers import D16_NETWORKS
    from uvms_jax.settings import from_mapping

    paper = surrogate.SurrogateSettings()  # the paper-sized defaults of configs/surrogate.yaml
    overrides = {"index_form": {"jacobian": args.jacobian}}
    if args.max_hidden is not None:
        overrides["ffbn"] = {"max_hidden": {"w": paper.ffbn.max_hidden.w, "kci": args.max_hidden}}
    if args.n_train is not None:
        overrides["data"] = {"n_train": {"w": paper.data.n_train.w, "kci": args.n_train}}
    s = from_mapping(surrogate.SurrogateSettings, overrides)
    f, paper_units = s.ffbn, D16_NETWORKS[NETWORK]["hidden_units"]
    n_train, n_test = s.data.n_train.kci, s.data.n_test

    # The keys of surrogate.run_surrogates, so these are the networks of a design run.
    _, k_kci, k_ffbn, _ = jax.random.split(jax.random.key(s.seed), 4)
    k_net = jax.random.fold_in(k_ffbn, s.networks.index(NETWORK))
    t0 = time.perf_counter()
    data = surrogate.make_dataset(k_kci, kin.uvms12(), s.sampling.to_sampling(), n_train + n_test, "kci",
                                  jax.numpy.float64, form=s.index_form)
    train, test = data.split(n_train)
    data_seconds = time.perf_counter() - t0
    device = jax.devices()[0]
    earlier = json.loads(args.resume.read_text()) if args.resume is not None else None
    step = args.step if args.step is not None else f.hidden_step
    record = {
        "benchmark": "surrogate_sizes", "network": NETWORK,
        "command": " ".join(["python benchmarks/surrogate_sizes.py", *sys.argv[1:]]),
        "device": device.device_kind, "platform": device.platform, "python": platform.python_version(),
        "jax": jax.__version__, "jacobian": args.jacobian, "train_dtype": s.train_dtype,
        "n_train": n_train, "n_test": n_test, "kci_min": float(data.y.min()), "kci_max": float(data.y.max()),
        "error_goal": f.error_goal, "max_hidden": f.max_hidden.kci, "trainer": f.trainer,
        "target_mse": f.target_mse.kci, "max_epochs": f.max_epochs, "paper_units": paper_units,
        "data_seconds": data_seconds, "steps": [], "finished": False, "hidden_step": step,
    }
    start, k_loop = 1, k_net
    record["parts"] = [{"from": 1, "step": step, "device": device.device_kind}]
    if earlier is not None:
        start, k_loop = _resume(record, earlier, args, step, k_loop, device.device_kind)

    def save(step=None, loop="design loop"):
        if step is not None:
            # An FFBN has no spread (NaN, which JSON does not hold).
            record["steps"].append({k: v for k, v in step._asdict().items() if k != "spread"} | {"loop": loop})
        if args.out is not None:
            write_json(args.out, _summary(record))

    design = surrogate.design_ffbn(
        k_loop, train, test, error_goal=f.error_goal, max_hidden=f.max_hidden.kci, hidden_start=start, hidden_step=step,
        trainer=f.trainer, target_mse=f.target_mse.kci, max_epochs=f.max_epochs, adam_steps=f.adam.steps,
        adam_learning_rate=f.adam.learning_rate, together=f.together, callback=save)
    if not any(st["size"] == paper_units for st in record["steps"]):
        # The loop's key of this size: design_ffbn splits its key once per size, from size 1.
        key = k_net
        for _ in range(paper_units - 1):
            key, _ = jax.random.split(key)
        alone = surrogate.design_ffbn(
            key, train, test, error_goal=f.error_goal, max_hidden=paper_units, hidden_start=paper_units,
            trainer=f.trainer, target_mse=f.target_mse.kci, max_epochs=f.max_epochs)
        save(alone.steps[0], loop="paper size alone")
    record["finished"] = True
    record["design_seconds"] = design.seconds + ((earlier or {}).get("design_seconds") or 0.0)
    save()
    print(json_text(_summary(record)))


def _summary(record: dict) -> dict:
    """``record`` with the figures read from its steps: the smallest size below the goal (or
    None), the best size and its error, and the error at the paper's size."""
    loop = [st for st in record["steps"] if st["loop"] == "design loop"]
    met = [st for st in loop if st["test_error"] < record["error_goal"]]
    best = min(loop, key=lambda st: st["test_error"]) if loop else None
    paper = next((st for st in record["steps"] if st["size"] == record["paper_units"]), None)
    return {**record, "met_goal": bool(met), "smallest_size_meeting_goal": met[0]["size"] if met else None,
            "largest_size_tried": max((st["size"] for st in loop), default=None),
            "best_size": best["size"] if best else None, "best_error": best["test_error"] if best else None,
            "error_at_paper_units": paper["test_error"] if paper else None}


if __name__ == "__main__":
    main()
