"""Fixtures of the pipeline tests."""

import importlib

import pytest
from _pipeline_helpers import EXPERIMENTS  # noqa: F401  (puts experiments/ on sys.path)


@pytest.fixture(scope="module")
def pipeline():
    return importlib.import_module("pipeline")


@pytest.fixture(scope="module")
def gather():
    return importlib.import_module("gather")
