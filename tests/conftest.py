"""Suite-wide fixtures: the disk cache of setup results lives in a temporary directory."""

from __future__ import annotations

import os

import pytest


@pytest.fixture(scope="session", autouse=True)
def _temporary_setup_cache(tmp_path_factory):
    """Point FLEXMVM_CACHE_DIR (read at every cache access, inherited by CLI subprocesses) at a
    session temporary directory, so tests never read or fill the user's cache."""
    old = os.environ.get("FLEXMVM_CACHE_DIR")
    os.environ["FLEXMVM_CACHE_DIR"] = str(tmp_path_factory.mktemp("flexmvm-cache"))
    yield
    if old is None:
        os.environ.pop("FLEXMVM_CACHE_DIR", None)
    else:
        os.environ["FLEXMVM_CACHE_DIR"] = old
