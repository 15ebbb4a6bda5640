"""Fixtures of the pipeline tests."""

import pytest
from _pipeline_helpers import load_experiment


@pytest.fixture(scope="module")
def pipeline():
    return load_experiment("pipeline")


@pytest.fixture(scope="module")
def gather():
    return load_experiment("gather")
