"""Shared fixtures of the dicesim module's tests (run through CTest: python/CMakeLists.txt).

Under CI=true a dependency that is missing fails the test instead of skipping it: the suite must
prove what it claims on CI, not skip silently.
"""
import importlib
import json
import os
import subprocess
from pathlib import Path

import pytest

SOURCE_DIR = Path(os.environ.get("DICESIM_SOURCE_DIR", Path(__file__).resolve().parents[2]))
DIE1 = "scenes/paper/die1.toml"  # relative to SOURCE_DIR, as the CLI is given it
os.chdir(SOURCE_DIR)  # scene paths as the CLI is given them, in the module and in the CLI


def require(module):
    """Imports `module`; a missing one skips the test, or fails it under CI=true."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        if os.environ.get("CI") == "true":
            pytest.fail(f"{module} is required under CI=true (scripts/setup installs it): {e}")
        pytest.skip(f"{module} not installed")


def cli_binary():
    path = os.environ.get("DICESIM_BINARY", str(SOURCE_DIR / "build/apps/dicesim"))
    if not Path(path).exists():
        if os.environ.get("CI") == "true":
            pytest.fail(f"the dicesim CLI is required under CI=true: {path} does not exist")
        pytest.skip(f"no CLI at {path}")
    return path


def run_cli(*args, check=True):
    """Runs the dicesim CLI in the source folder; returns the CompletedProcess."""
    p = subprocess.run([cli_binary(), *args], cwd=SOURCE_DIR, capture_output=True, text=True, timeout=120)
    if check and p.returncode != 0:
        raise AssertionError(f"dicesim {' '.join(args)} failed ({p.returncode}): {p.stderr}")
    return p


def cli_json(*args):
    return json.loads(run_cli(*args, "--json").stdout)


def without_timing(d):
    """A toss --json object without what depends on the clock (auto's pilot time too)."""
    out = {k: v for k, v in d.items() if k not in ("elapsed_s", "tosses_per_s")}
    if out.get("pilot"):
        out["pilot"] = {k: v for k, v in out["pilot"].items() if k != "seconds"}
    return out


@pytest.fixture(scope="session")
def dicesim():
    require("numpy")
    import dicesim as module
    return module


@pytest.fixture(scope="session")
def die1(dicesim):
    return dicesim.load_scene(DIE1)
