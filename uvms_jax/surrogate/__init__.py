"""Neural-network surrogates of the dexterity indices w and KCI (dexterity paper; docs/theory.md §4).

Datasets D1 (θ1…θ11 → KCI) and D2 (θ5…θ11 → w) of the 12-DOF UVMS, sampled as in the paper's
Fig. 7, labelled from the geometric Jacobian or the paper's spatial-twist form (:class:`IndexForm`); a feed-forward network (FFBN: tanh hidden layer, linear output) trained by
Levenberg–Marquardt or Adam; a Gaussian RBF network (RBFN) grown greedily; the paper's design
loops; save/load. Every network has ``index_fn(q)`` with ``q: (..., 12)`` so it can replace the
analytic index (``analytic_index_fn``) wherever a batch of configurations is scored.

The whole design run is one stage: ``run_surrogates(key, chain, settings) -> SurrogateRun``
(settings: :class:`SurrogateSettings`, mirroring ``configs/surrogate.yaml``), and
``write_surrogates(run, out)`` writes its report, figures, datasets and networks.

For an arm on a vehicle, :func:`run_reach_map` learns the arm's best manipulability at a tool
pose seen from its base (:class:`ReachMap`), the inner part of the docking fitness, and
:class:`SurrogateDockingProblem` / :func:`dock_with_map` dock with it: the GA on the map
proposes, the analytic fitness confirms and refines.

Error metric of the index surrogates: the maximum relative test error ``max |(T − S)/T|`` (paper eq. 21).
"""

from uvms_jax.surrogate._adam import fit_adam
from uvms_jax.surrogate._dataset import INDEX_INPUTS
from uvms_jax.surrogate._dataset import INDEX_NAMES
from uvms_jax.surrogate._dataset import Dataset
from uvms_jax.surrogate._dataset import Sampling
from uvms_jax.surrogate._dataset import analytic_index
from uvms_jax.surrogate._dataset import analytic_index_fn
from uvms_jax.surrogate._dataset import index_inputs
from uvms_jax.surrogate._dataset import load_dataset
from uvms_jax.surrogate._dataset import make_dataset
from uvms_jax.surrogate._dataset import mb_offset
from uvms_jax.surrogate._dataset import sample_configurations
from uvms_jax.surrogate._dataset import save_dataset
from uvms_jax.surrogate._design import Design
from uvms_jax.surrogate._design import DesignStep
from uvms_jax.surrogate._design import design_ffbn
from uvms_jax.surrogate._design import design_rbfn
from uvms_jax.surrogate._design import max_relative_error
from uvms_jax.surrogate._ffbn import FFBN
from uvms_jax.surrogate._ffbn import MLP
from uvms_jax.surrogate._ffbn import folded_layers
from uvms_jax.surrogate._ffbn import init_ffbn
from uvms_jax.surrogate._ffbn import init_ffbns
from uvms_jax.surrogate._ffbn import mlp_apply
from uvms_jax.surrogate._ffbn import pad_hidden
from uvms_jax.surrogate._ffbn import padded_width
from uvms_jax.surrogate._ffbn import predict_side_by_side
from uvms_jax.surrogate._ffbn import trim_hidden
from uvms_jax.surrogate._ffbn import train_ffbn_adam
from uvms_jax.surrogate._ffbn import train_ffbn_lm
from uvms_jax.surrogate._ffbn import train_ffbns_adam
from uvms_jax.surrogate._ffbn import train_ffbns_lm
from uvms_jax.surrogate._form import JACOBIAN_FORMS
from uvms_jax.surrogate._form import IndexForm
from uvms_jax.surrogate._io import load_network
from uvms_jax.surrogate._io import save_network
from uvms_jax.surrogate._lm import LevenbergMarquardt
from uvms_jax.surrogate._lm import LMHyperParams
from uvms_jax.surrogate._lm import LMState
from uvms_jax.surrogate._lm import fit_lm
from uvms_jax.surrogate._lm import levenberg_marquardt
from uvms_jax.surrogate._plots import plot_ffbn_design
from uvms_jax.surrogate._plots import plot_rbfn_design
from uvms_jax.surrogate._plots import plot_training
from uvms_jax.surrogate._rbfn import RBFN
from uvms_jax.surrogate._rbfn import RBFNFit
from uvms_jax.surrogate._rbfn import fit_rbfn
from uvms_jax.surrogate._rbfn import fit_rbfn_arrays
from uvms_jax.surrogate._reach import MapDocking
from uvms_jax.surrogate._reach import ReachData
from uvms_jax.surrogate._reach import ReachMap
from uvms_jax.surrogate._reach import ReachMapRun
from uvms_jax.surrogate._reach import ReachMapSettings
from uvms_jax.surrogate._reach import SurrogateDockingProblem
from uvms_jax.surrogate._reach import dock_with_map
from uvms_jax.surrogate._reach import fit_reach_map
from uvms_jax.surrogate._reach import reach_dataset
from uvms_jax.surrogate._reach import reach_features
from uvms_jax.surrogate._reach import run_reach_map
from uvms_jax.surrogate._run import SurrogateRun
from uvms_jax.surrogate._run import acceptance_figures
from uvms_jax.surrogate._run import run_surrogates
from uvms_jax.surrogate._scaler import Scaler
from uvms_jax.surrogate._scaler import fit_scaler
from uvms_jax.surrogate._settings import NETWORK_NAMES
from uvms_jax.surrogate._settings import AcceptanceSettings
from uvms_jax.surrogate._settings import AdamSettings
from uvms_jax.surrogate._settings import DataSettings
from uvms_jax.surrogate._settings import FFBNSettings
from uvms_jax.surrogate._settings import IndexFloats
from uvms_jax.surrogate._settings import IndexInts
from uvms_jax.surrogate._settings import RBFNSettings
from uvms_jax.surrogate._settings import SamplingSettings
from uvms_jax.surrogate._settings import SurrogateSettings
from uvms_jax.surrogate._settings import TimingSettings
from uvms_jax.surrogate._settings import split_network_name
from uvms_jax.surrogate._timing import chunk_for
from uvms_jax.surrogate._timing import tile_batch
from uvms_jax.surrogate._timing import time_index_fn
from uvms_jax.surrogate._timing import xla_flops_per_sample
from uvms_jax.surrogate._write import write_surrogates
