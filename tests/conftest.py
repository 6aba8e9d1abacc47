"""Suite-wide fixtures: the disk cache of setup results lives in a temporary directory."""

from __future__ import annotations

import os

import pytest


@pytest.fixture(scope="session", autouse=True)
def _temporary_setup_cache(tmp_path_factory):
    """Point FLEXMVM_CACHE_DIR (read at every cache access, inherited by CLI subprocesses) at a
    session temporary directory, so tests never read or fill the user's cache. Under
    pytest-xdist the workers of one run share it (the run's base temporary directory): the
    seed rods' FE models and bases are then built once per run, not once per worker; entries
    are written atomically with a checksum (setup_cache.store), so two workers writing the
    same entry leave one whole copy."""
    old = os.environ.get("FLEXMVM_CACHE_DIR")
    os.environ["FLEXMVM_CACHE_DIR"] = str(_shared_cache_dir(tmp_path_factory))
    yield
    if old is None:
        os.environ.pop("FLEXMVM_CACHE_DIR", None)
    else:
        os.environ["FLEXMVM_CACHE_DIR"] = old


def _shared_cache_dir(tmp_path_factory):
    """The run's cache directory: beside the workers' base temporary directories under xdist
    (their common parent belongs to this run alone), else a session temporary directory."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        path = tmp_path_factory.getbasetemp().parent / "flexmvm-cache"
        path.mkdir(exist_ok=True)
        return path
    return tmp_path_factory.mktemp("flexmvm-cache")
