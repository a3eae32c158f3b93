"""Fixtures of the Python module's tests: the repository, the CLI binary, a small scene."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def cli():
    """The `photon` command line of this checkout (built if missing)."""
    exe = ROOT / "target" / "release" / "photon"
    if not exe.exists():
        subprocess.run(
            ["cargo", "build", "--release", "--bin", "photon"], cwd=ROOT, check=True
        )
    return exe


@pytest.fixture(scope="session")
def glass():
    """A Cornell box with a glass sphere: every component layer is non-zero."""
    return ROOT / "scenes" / "cornell-glass.pbrt"


def run_cli(cli, *args):
    """Runs the CLI; its stdout, or a failure showing its stderr."""
    r = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r.stdout


def rss_bytes():
    """This process's resident memory."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
