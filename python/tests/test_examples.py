"""examples/python run as a user runs them, and their pictures are written."""
import os
import re
import subprocess
import sys

from conftest import EXAMPLES

PNG = b"\x89PNG\r\n\x1a\n"


def run(script, *args):
    env = dict(os.environ)
    env.pop("DISPLAY", None)  # no window in a test
    r = subprocess.run([sys.executable, str(EXAMPLES / "python" / script), *map(str, args)],
                       capture_output=True, text=True, env=env, check=False)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout


def test_the_probe_controller_pushes_and_plots_the_force(tmp_path):
    out = run("probe_controller.py", tmp_path)
    peak = float(re.search(r"peak force ([0-9.e+-]+) N", out).group(1))
    assert 0.005 < peak < 1.0  # a 20 N/m block pushed 8 mm: centinewtons
    assert (tmp_path / "probe_force.png").read_bytes().startswith(PNG)


def test_the_stiffness_sweep_finds_a_stiffer_prostate_deforms_less(tmp_path):
    out = run("stiffness_sweep.py", tmp_path, "--quick")
    rows = re.findall(r"K = +([0-9.]+) N/m: empty \(50 mL\) ([0-9.]+) %, full \(400 mL\) ([0-9.]+) %",
                      out)
    assert len(rows) == 2
    (_, soft_empty, soft_full), (_, stiff_empty, stiff_full) = rows
    assert float(stiff_empty) < float(soft_empty) and float(stiff_full) < float(soft_full)
    assert (tmp_path / "stiffness_sweep.png").read_bytes().startswith(PNG)
