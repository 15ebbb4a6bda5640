"""Files of a surrogate run: results.json, design and training figures, datasets and networks."""

from __future__ import annotations

from pathlib import Path

from uvms_jax.files import write_json
from uvms_jax.surrogate._dataset import save_dataset
from uvms_jax.surrogate._io import save_network
from uvms_jax.surrogate._plots import plot_ffbn_design, plot_rbfn_design, plot_training
from uvms_jax.surrogate._run import DATASET_NAMES, SurrogateRun
from uvms_jax.surrogate._settings import split_network_name


def write_surrogates(run: SurrogateRun, out: Path) -> Path:
    """Write ``run`` into the directory ``out`` (created if missing); returns the report's path.

    Files::

      results.json                  ``run.report``
      data/d1_{train,test}.npz/json    KCI datasets; data/d2_*: w datasets (with seed and chain)
      networks/<name>.npz/json     each network (with design seconds and whether it met the goal)
      ffbn_<index>_design.png      test error vs hidden neurons (Figs. 10/14)
      rbfn_<index>_design.png      test error and units vs spread (Figs. 8/12)
      training.png                 training mse of each selected network (Figs. 9/11/13/15)
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for index, (train, test) in run.sets.items():
        for part, d in (("train", train), ("test", test)):
            save_dataset(out / "data" / f"{DATASET_NAMES[index]}_{part}", d, seed=run.settings.seed,
                         chain=run.chain_name)
    plots = {"ffbn": (plot_ffbn_design, run.settings.ffbn.error_goal),
             "rbfn": (plot_rbfn_design, run.settings.rbfn.error_goal)}
    for name, d in run.designs.items():
        save_network(out / "networks" / name, d.network, design_seconds=d.seconds, met=d.met)
        plot, goal = plots[split_network_name(name)[0]]
        plot(name, d, goal, out / f"{name}_design.png")
    plot_training(run.designs, out / "training.png")
    path = out / "results.json"
    return write_json(path, run.report)
