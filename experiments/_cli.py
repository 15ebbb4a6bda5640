"""What every experiment's command line shares: one-line configuration errors, quiet backend
probing, and a ``--help`` that lists the experiment's own config groups.

An experiment reads its config inside ``with _cli.config_errors():`` and ends with
``_cli.run(main)`` instead of ``main()``. A configuration error — a value of the wrong type or
outside its allowed values, a file that does not exist (``uvms_jax.settings.SettingsError``,
raised while the settings are built, before any stage runs), an unknown key or group option, an
override that cannot be parsed, a missing ``???`` value — then prints one line naming the key
(every bad key of the settings) and its allowed values, and exits with status 2, without a
traceback::

    $ python experiments/schedule.py sched.grasp.iterations=abc
    error: sched.grasp.iterations: expected an integer, got 'abc'
    $ python experiments/docking.py ga.mutation_rate=2.0 n_runs=-1
    error: ga.mutation_rate: expected a value in [0, 1], got 2.0; n_runs: expected a value >= 1, got -1

A run folder that holds an earlier run (its results, or the ``RUNNING`` marker of a run that
did not end) is refused the same way, naming the marker's run and when it started, unless
``--overwrite`` (or the override ``overwrite=true``) is given; an experiment whose config asks
for it (``hydra.callbacks``: :class:`RefuseUsedRunFolder`) checks before Hydra writes anything
into the folder. Ctrl-C (SIGINT) and SIGTERM stop a run alike: what it finished is on disk, its
folder marked ``interrupted``; exit status 130 and 143.

Any other exception keeps its full traceback; ``HYDRA_FULL_ERROR=1`` shows it for
configuration errors too. Importing this module (the scripts' folder is on ``sys.path``) also
registers the ``uvms_config_groups`` resolver that ``configs/hydra/help/uvms.yaml`` uses.
"""

from __future__ import annotations

import contextlib
import importlib
import logging
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

from hydra.core.global_hydra import GlobalHydra
from hydra.experimental.callback import Callback
from hydra.core.hydra_config import HydraConfig
from hydra.errors import ConfigCompositionException, MissingConfigException, OverrideParseException
import omegaconf._utils
import yaml
from omegaconf import OmegaConf
from omegaconf.errors import ConfigAttributeError, ConfigKeyError, OmegaConfBaseException

from uvms_jax.files import EXIT_INTERRUPTED, EXIT_TERMINATED, UsedFolderError, refuse_used_folder, sigterm_as_interrupt
from uvms_jax.settings import SettingsError, bounded_yaml_loader

USAGE_EXIT = 2  # as argparse: the command line is wrong, nothing ran
CONFIG_ERRORS = (SettingsError, ConfigCompositionException, OverrideParseException, OmegaConfBaseException,
                 UsedFolderError, yaml.YAMLError)
OVERWRITE_FLAG = "--overwrite"  # the command-line flag for the override `overwrite=true`
# Read before run() sets it: the user's own HYDRA_FULL_ERROR=1 asks for tracebacks.
SHOW_TRACEBACK = os.environ.get("HYDRA_FULL_ERROR") == "1"

# Every config file Hydra reads goes through OmegaConf's YAML loader: bounded here
# (uvms_jax.settings.bounded_yaml_loader), so an alias bomb or a repeated key is one line naming
# the file and line, not a process filling the memory or the last key winning.
_omegaconf_yaml_loader = omegaconf._utils.get_yaml_loader
omegaconf._utils.get_yaml_loader = lambda: bounded_yaml_loader(_omegaconf_yaml_loader())

# JAX logs at INFO which platforms it could not load ("Unable to initialize backend 'tpu'") and
# warns when a GPU exists without a CUDA jaxlib; neither says anything about the run.
logging.getLogger("jax._src.xla_bridge").setLevel(logging.ERROR)


def one_line(e: BaseException) -> str:
    """A configuration error as one line that names the key (or config) at fault."""
    cause = e.__cause__
    if isinstance(e, yaml.MarkedYAMLError) or isinstance(cause, yaml.MarkedYAMLError):
        y = e if isinstance(e, yaml.MarkedYAMLError) else cause
        mark = y.problem_mark or y.context_mark
        where = f"{mark.name}, line {mark.line + 1}: " if mark is not None else ""
        return f"{where}{' '.join(str(y.problem or y.context).split())}"
    if isinstance(e, MissingConfigException):
        first = str(e).splitlines()[0].strip()
        return f"{first}; available: {', '.join(e.options)}" if e.options else first
    if isinstance(e, OmegaConfBaseException) or isinstance(cause, OmegaConfBaseException):
        oc = e if isinstance(e, OmegaConfBaseException) else cause
        key, msg = getattr(oc, "full_key", None), str(getattr(oc, "msg", None) or oc).splitlines()[0].strip()
        if isinstance(oc, (ConfigKeyError, ConfigAttributeError)) and key:  # not in a struct config
            return f"{key}: unknown key"
        return f"{key}: {msg}" if key else msg
    return " ".join(line.strip() for line in str(e).splitlines() if line.strip())


@contextlib.contextmanager
def config_errors() -> Iterator[None]:
    """Inside it, a configuration error (``CONFIG_ERRORS``) prints one line and exits with
    status 2 (``SystemExit``, which Hydra's job runner passes on without reporting the job as
    failed in a second line)."""
    try:
        yield
    except CONFIG_ERRORS as e:
        if SHOW_TRACEBACK:
            raise
        print(f"error: {one_line(e)}", file=sys.stderr)
        sys.exit(USAGE_EXIT)


def run(main: Callable[[], Any]) -> None:
    """Run a ``@hydra.main`` function; errors in composing the config (unknown key or group
    option, bad override) → one line on stderr, exit 2; Ctrl-C → one line, exit 130, SIGTERM
    → the same, exit 143 (what the run had finished is on disk, its folder marked).
    ``--overwrite`` on the command line is the override ``overwrite=true``."""
    # Hydra prints its own multi-line report and exits 1 unless HYDRA_FULL_ERROR is set; with
    # it set, the exception reaches this frame.
    os.environ["HYDRA_FULL_ERROR"] = "1"
    if OVERWRITE_FLAG in sys.argv[1:]:
        sys.argv = [a for a in sys.argv if a != OVERWRITE_FLAG] + ["overwrite=true"]
    with sigterm_as_interrupt() as terminated:
        try:
            with config_errors():
                main()
        except KeyboardInterrupt:
            signal = "SIGTERM" if terminated() else "SIGINT"
            print(f"interrupted ({signal}): the partial results and the run folder's RUNNING marker say how far "
                  "it got", file=sys.stderr)
            sys.exit(EXIT_TERMINATED if terminated() else EXIT_INTERRUPTED)


class RefuseUsedRunFolder(Callback):
    """A Hydra callback (``hydra.callbacks``) that refuses a run folder (``hydra.run.dir``)
    holding an earlier run before Hydra writes into it (``.hydra/``, the log), unless the
    config's ``overwrite`` is true: the earlier run's files stay as they were.

    Args:
      runner: the module of the experiment's runner (e.g. ``uvms_jax.pipeline``): its
        ``RUN_FILES`` (a folder holding any of them holds a run) and ``RETRY`` (what a refused
        user does instead), which the runner's own check uses too.
    """

    def __init__(self, runner: str) -> None:
        self.runner = runner

    def on_run_start(self, config, **kwargs: Any) -> None:
        if OmegaConf.select(config, "overwrite", default=False) is True:
            return
        runner = importlib.import_module(self.runner)
        with config_errors():  # one line, exit 2 (Hydra turns a callback's exception into a warning)
            refuse_used_folder(OmegaConf.select(config, "hydra.run.dir"), runner.RUN_FILES, runner.RETRY)


@contextlib.contextmanager
def quiet(logger: str) -> Iterator[None]:
    """Inside it, ``logger`` logs warnings and errors only (a check that repeats work the run
    logs itself)."""
    log = logging.getLogger(logger)
    level = log.level
    log.setLevel(logging.WARNING)
    try:
        yield
    finally:
        log.setLevel(level)


def config_file(group: str) -> str:
    """The file of the option chosen for config group ``group`` (e.g. ``scenario`` or
    ``scenario@baseline``) in this job's config search path (relative to the working directory
    where inside it), or ``group/option.yaml`` where it is not a plain file (call inside a
    Hydra context)."""
    hc = HydraConfig.get()
    choice = hc.runtime.choices.get(group)
    folder = group.split("@", 1)[0]
    for source in hc.runtime.config_sources:
        path = Path(source.path) / folder / f"{choice}.yaml"
        if source.schema == "file" and path.is_file():
            return os.path.relpath(path) if path.resolve().is_relative_to(Path.cwd()) else str(path)
    return f"{folder}/{choice}.yaml"


def overridden(*keys: str) -> list[str]:
    """The command-line overrides of this job (``key=value``) that set one of ``keys`` (a config
    group such as ``sched/weights`` or a key such as ``sched.weights``) or a key below them."""

    def hits(override: str) -> bool:
        key = override.lstrip("+~").split("=", 1)[0].split("@", 1)[0]
        return any(key == k or key.startswith(k + ".") or key.startswith(k + "/") for k in keys)

    return [o for o in HydraConfig.get().overrides.task if hits(o)]


def reject_unused_weights(source_kind: str) -> None:
    """Raise ``SettingsError`` when the command line sets metric weights that a ready cost
    matrix (``source_kind == "matrix"``) would ignore: an override that changes nothing."""
    if source_kind != "matrix":
        return
    ov = overridden("sched/weights", "sched.weights")
    if ov:
        raise SettingsError(f"{ov[0]}: the weights are unused with a ready cost matrix (sched/source=thesis_matrix); "
                            "they apply to metric sources (sched/source=synthetic or edges_csv)")


def _config_groups(*, _root_: Any) -> str:
    """The app's config groups and their options, one line each (the selected one starred):
    the groups of this config's defaults list, from ``hydra.runtime.choices``."""
    loader = GlobalHydra.instance().config_loader()
    lines = []
    for group, choice in sorted(_root_.hydra.runtime.choices.items()):
        if group.startswith("hydra/"):
            continue
        options: Sequence[str] = loader.get_group_options(group.split("@", 1)[0])
        lines.append(f"{group}: " + ", ".join(f"{o}*" if o == choice else o for o in options))
    return "\n".join(lines)


OmegaConf.register_new_resolver("uvms_config_groups", _config_groups, replace=True)
