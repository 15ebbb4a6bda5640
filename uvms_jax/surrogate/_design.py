"""The paper's design loops (dexterity paper §3.3–3.4, Fig. 6) and the test-error metric.

Test error (eq. 21): ``e = max_i |(T_i − S_i) / T_i|`` over the test set — the *maximum*
relative error, not a mean; T is the analytic index, S the network output. It is meaningful
only where T stays away from 0 (the paper's sampling keeps w and KCI well above 0).

- FFBN: hidden neurons H = 1, 2, … (``hidden_step``) up to ``max_hidden``; each network is
  trained (Levenberg–Marquardt to E_mse or L_epochs, or Adam) and tested; the loop stops at the
  first network with ``e < E``.
- RBFN: for spread = s0, s0 + st_spread, … ≤ L_s: greedy design until training mse ≤ E_th
  (or the unit limit), then test; stop at the first spread with ``e < E``.

The outer loops are Python loops over networks; each network's training is one jitted call, or
several sizes' in one vmapped call (``together``). FFBNs are trained zero-padded to the next
power of two of hidden units (at least 8), which gives the same network and compiles the
trainer once per width rather than once per size; the RBFN spread is traced, so a spread
search compiles once.
"""

from __future__ import annotations

import logging
import time
from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from uvms_jax import progress
from uvms_jax.surrogate._dataset import Dataset
from uvms_jax.surrogate._ffbn import FFBN, init_ffbns, padded_width, predict_side_by_side, train_ffbns_adam, train_ffbns_lm
from uvms_jax.surrogate._lm import LMHyperParams
from uvms_jax.surrogate._rbfn import RBFN, fit_rbfn

log = logging.getLogger(__name__)
TRAINERS = ("lm", "adam")


def max_relative_error(target, prediction) -> Array:
    """Paper eq. 21: ``max |(T − S) / T|`` over all entries; ``inf`` if some ``T == 0``."""
    target, prediction = jnp.asarray(target), jnp.asarray(prediction)
    if target.shape != prediction.shape:
        raise ValueError(f"target and prediction shapes differ: {target.shape} vs {prediction.shape}")
    zero = target == 0
    rel = jnp.where(zero, jnp.inf, jnp.abs(target - prediction) / jnp.where(zero, 1.0, jnp.abs(target)))
    return jnp.max(rel)


class DesignStep(NamedTuple):
    """One network tried by a design loop.

    Attributes:
      size: hidden neurons (FFBN) or RBF units (RBFN).
      spread: RBF spread (normalised input units); NaN for an FFBN.
      test_error: max relative test error (eq. 21).
      train_mse: final training mse [index units²].
      epochs: training epochs (FFBN) or added units (RBFN).
      seconds: wall time of training + testing, compilation included.
    """

    size: int
    spread: float
    test_error: float
    train_mse: float
    epochs: int
    seconds: float


class Design(NamedTuple):
    """Result of a design loop.

    Attributes:
      network: the first network that met the error goal, else the one with the lowest test error.
      steps: every network tried, in order.
      met: whether ``network`` meets the goal.
      seconds: total wall time.
      history: training-mse history of ``network`` [index units²] (per epoch / per unit).
    """

    network: FFBN | RBFN
    steps: list[DesignStep]
    met: bool
    seconds: float
    history: np.ndarray


def _check_pair(train: Dataset, test: Dataset) -> None:
    if train.index != test.index or tuple(train.inputs) != tuple(test.inputs):
        raise ValueError(f"train ({train.index}, {train.inputs}) and test ({test.index}, {test.inputs}) sets differ")


def _size_keys(key: Array, n: int) -> list[Array]:
    """One key per network size, split as a one-by-one loop over the sizes splits it."""
    keys = []
    for _ in range(n):
        key, sub = jax.random.split(key)
        keys.append(sub)
    return keys


def _train_group(nets: list, train: Dataset, width: int, trainer: str, lm: dict, adam: dict) -> list[tuple]:
    """Train FFBNs side by side, padded to ``width`` hidden units, by Levenberg–Marquardt
    (``lm``: keyword arguments of :func:`train_ffbns_lm`) or Adam (``adam``: of
    :func:`train_ffbns_adam`). Returns ``(net, train mse, epochs, mse history)`` per network."""
    if trainer == "lm":
        return [(net, float(state.mse), int(state.epoch), history) for net, state, history in
                train_ffbns_lm(nets, train, pad_to=width, **lm)]
    return [(net, float(history[-1]), adam["steps"], history) for net, history in
            train_ffbns_adam(nets, train, pad_to=width, **adam)]


def design_ffbn(
    key: Array,
    train: Dataset,
    test: Dataset,
    *,
    error_goal: float = 0.02,
    max_hidden: int = 100,
    hidden_start: int = 1,
    hidden_step: int = 1,
    trainer: str = "lm",
    target_mse: float = 1e-3,
    max_epochs: int = 100,
    lm_hyper: LMHyperParams = LMHyperParams(),
    adam_steps: int = 2000,
    adam_learning_rate: float = 1e-2,
    together: int = 1,
    callback: Callable[[DesignStep], None] | None = None,
) -> Design:
    """Grow an FFBN until its max relative test error < ``error_goal`` (paper Fig. 6a).

    Args:
      key: PRNG key (split once per network size).
      train, test: datasets of the same index.
      error_goal: E (paper: 0.02).
      max_hidden: L_iter (paper: 100).
      hidden_start, hidden_step: sizes tried are ``hidden_start, +hidden_step, …``.
      trainer: "lm" (Levenberg–Marquardt, E_mse/L_epochs) or "adam" (``adam_steps``).
      target_mse: E_mse in squared index units (paper: 1e-3 for w, 5e-6 for KCI).
      max_epochs: L_epochs (paper: 100).
      together: up to this many consecutive sizes of one padded width train side by side in
        one vmapped call (each as alone up to round-off, from the key the one-by-one loop gives it);
        the loop still reports and stops at the first size that meets the goal, so sizes
        trained beyond it in its call are dropped. A group is initialised, trained and tested
        in one compiled call each, where one size at a time compiles every size anew (most of
        a GPU's time); 1 trains one size at a time.
      callback: called with each :class:`DesignStep` (progress reporting).
    """
    _check_pair(train, test)
    if trainer not in TRAINERS:
        raise ValueError(f"unknown trainer {trainer!r}; expected one of {TRAINERS}")
    if not (1 <= hidden_start <= max_hidden and hidden_step >= 1 and together >= 1):
        raise ValueError(f"need 1 <= hidden_start <= max_hidden, hidden_step >= 1 and together >= 1, got "
                         f"{hidden_start}, {max_hidden}, {hidden_step}, {together}")
    search = _Search(error_goal, callback)
    sizes = list(range(hidden_start, max_hidden + 1, hidden_step))
    keys = _size_keys(key, len(sizes))
    # The loop stops at the first size that meets the target: the bar's total is the most it can take.
    with progress.bar(total=len(sizes), desc="FFBN design", unit="size") as bar:
        for group in _groups(sizes, together):
            t0 = time.perf_counter()
            nets = init_ffbns([keys[i] for i in group], [sizes[i] for i in group], train)
            width = padded_width(sizes[group[-1]])
            trained = _train_group(nets, train, width, trainer, dict(max_epochs=max_epochs, target_mse=target_mse,
                                                                     hyper=lm_hyper),
                                   dict(steps=adam_steps, learning_rate=adam_learning_rate))
            # One compiled call per width: FFBN.predict would compile once per size.
            predictions = predict_side_by_side([net for net, *_ in trained], test.x)
            errors = [float(max_relative_error(test.y, p)) for p in predictions]
            seconds = (time.perf_counter() - t0) / len(group)
            for (net, mse, epochs, history), err in zip(trained, errors):
                log.info("FFBN-%s H=%d: max rel test error %.4f, train mse %.3g, %d epochs, %.2f s",
                         train.index, net.hidden, err, mse, epochs, seconds)
                bar.update()
                history = np.asarray(history)
                if search.add(DesignStep(net.hidden, float("nan"), err, mse, epochs, seconds), net,
                              history[np.isfinite(history)]):
                    break
            if search.met:
                break
    return search.design()


class _Search:
    """The bookkeeping of a design loop: every step tried, the best network so far, whether one
    met the error goal, the time since the loop began."""

    def __init__(self, error_goal: float, callback: Callable[[DesignStep], None] | None):
        self.error_goal, self.callback = error_goal, callback
        self.t0 = time.perf_counter()
        self.steps: list[DesignStep] = []
        self.best: tuple | None = None  # (network, test error, its training history)
        self.met = False

    def add(self, step: DesignStep, net: FFBN | RBFN, history: np.ndarray) -> bool:
        """Record a network tried; True once its test error meets the goal (the loop stops)."""
        self.steps.append(step)
        if self.callback is not None:
            self.callback(step)
        if self.best is None or step.test_error < self.best[1]:
            self.best = (net, step.test_error, history)
        self.met = step.test_error < self.error_goal  # then it is the best: none before met it
        return self.met

    def design(self) -> Design:
        """The loop's result: the network that met the goal, else the best one."""
        return Design(self.best[0], self.steps, self.met, time.perf_counter() - self.t0, self.best[2])


def _groups(sizes: list[int], together: int) -> list[list[int]]:
    """Indices of ``sizes`` in runs of consecutive sizes of one padded width, at most ``together`` long."""
    groups: list[list[int]] = []
    for i, size in enumerate(sizes):
        if groups and len(groups[-1]) < together and padded_width(sizes[groups[-1][0]]) == padded_width(size):
            groups[-1].append(i)
        else:
            groups.append([i])
    return groups


def design_rbfn(
    train: Dataset,
    test: Dataset,
    *,
    error_goal: float = 0.02,
    spread_start: float = 1.0,
    spread_step: float = 1.0,
    spread_max: float = 10.0,
    target_mse: float = 1e-6,
    max_centres: int = 300,
    callback: Callable[[DesignStep], None] | None = None,
) -> Design:
    """Search the spread of a greedily grown RBFN (paper Fig. 6b).

    Args:
      train, test: datasets of the same index.
      error_goal: E (paper: 0.02).
      spread_start, spread_step, spread_max: spreads ``s0, s0 + st_spread, … ≤ L_s`` in
        normalised input units (paper: L_s = 10).
      target_mse: E_th, training mse at which unit addition stops [index units²].
      max_centres: unit limit per spread.
      callback: called with each :class:`DesignStep`.
    """
    _check_pair(train, test)
    if not (spread_start > 0 and spread_step > 0 and spread_max >= spread_start):
        raise ValueError(f"need 0 < spread_start <= spread_max and spread_step > 0, got "
                         f"{spread_start}, {spread_step}, {spread_max}")
    search = _Search(error_goal, callback)
    n_spreads = int(np.floor((spread_max - spread_start) / spread_step + 1e-9)) + 1
    with progress.bar(total=n_spreads, desc="RBFN design", unit="spread") as bar:
        for spread in spread_start + spread_step * np.arange(n_spreads):
            t0 = time.perf_counter()
            net, history = fit_rbfn(train, spread=float(spread), target_mse=target_mse, max_centres=max_centres)
            err = float(max_relative_error(test.y, net.predict(test.x)))
            step = DesignStep(net.n_centres, float(spread), err, float(history[-1]), net.n_centres, time.perf_counter() - t0)
            log.info("RBFN-%s spread %.3g: %d units, max rel test error %.4f, train mse %.3g, %.2f s",
                     train.index, spread, net.n_centres, err, step.train_mse, step.seconds)
            bar.update()
            if search.add(step, net, np.asarray(history)):
                break
    return search.design()
