"""Shared helpers: the program beside the module (PHYMUL_CLI) and the source tree's examples."""
import os
import pathlib
import subprocess

import pytest

SOURCE = pathlib.Path(os.environ.get("PHYMUL_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
EXAMPLES = SOURCE / "examples"


def cli():
    path = os.environ.get("PHYMUL_CLI")
    if not path:
        pytest.fail("PHYMUL_CLI is not set (ctest sets it to the built program)")
    return path


def run_cli(*args, threads=1):
    """The program with OMP_NUM_THREADS=threads: (exit code, stdout + stderr)."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    r = subprocess.run([cli(), *map(str, args)], capture_output=True, text=True, env=env,
                       check=False)
    return r.returncode, r.stdout + r.stderr
