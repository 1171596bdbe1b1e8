"""Fixtures for the Python suite: the built CLI (the oracle of "same results as the command line")
and the shared models. ctest sets LIMN_CLI, LIMN_SHARED_MODELS and PYTHONPATH."""

import json
import os
import pathlib
import subprocess

import pytest


@pytest.fixture(scope="session")
def models() -> pathlib.Path:
    path = pathlib.Path(os.environ.get("LIMN_SHARED_MODELS", "../shared/models"))
    if not path.is_dir():
        pytest.skip(f"no shared models at {path}")
    return path


@pytest.fixture(scope="session")
def cli():
    """Runs `limn ARGS...`; with json=True returns the parsed --json output."""
    exe = os.environ.get("LIMN_CLI", "limn")

    def run(*args, json_out=False, check=True):
        cmd = [exe, *map(str, args)] + (["--json"] if json_out else [])
        done = subprocess.run(cmd, capture_output=True, text=True)
        if check and done.returncode != 0:
            raise AssertionError(f"{cmd} exited {done.returncode}: {done.stderr}")
        return json.loads(done.stdout) if json_out else done

    return run
