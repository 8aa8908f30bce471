"""What the module's tests share: the source tree and the built `arbiter` command (the CMake test
sets ARBITER_SOURCE_DIR and ARBITER_CLI)."""

import os
import pathlib
import subprocess

import pytest

SOURCE = pathlib.Path(os.environ.get("ARBITER_SOURCE_DIR", pathlib.Path(__file__).parents[2]))


@pytest.fixture
def source():
    return SOURCE


@pytest.fixture
def cli():
    """Runs the built `arbiter` with the given arguments in the source tree."""
    command = os.environ.get("ARBITER_CLI")
    if not command:
        pytest.skip("ARBITER_CLI is not set (run through ctest)")

    def run(*args):
        return subprocess.run([command, *map(str, args)], cwd=SOURCE, capture_output=True,
                              text=True)

    return run
