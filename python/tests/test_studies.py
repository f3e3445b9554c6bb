"""The studies from Python: the tables the program prints, as dicts."""
import json

import pytest

import phymul
from conftest import run_cli


def test_truthcube_returns_the_programs_table(tmp_path):
    table = phymul.truthcube(cells=4, fem=False)
    code, output = run_cli("truthcube", "--cells", 4, "--no-fem", "--no-pictures", "-q", "-o", tmp_path)
    assert code == 0, output
    written = json.loads((tmp_path / "truthcube.json").read_text())
    for levels in (table["levels"], written["levels"]):
        for level in levels:
            level.pop("seconds")  # wall time
    assert table == written
    levels = table["levels"]
    strains = [level["strain"] for level in levels]
    assert len(levels) == 3 and strains == sorted(strains)
    # Against the measured beads: errors grow with the compression and stay millimetric.
    errors = [level["mean_error_mm"] for level in levels]
    assert errors == sorted(errors) and 0.0 < errors[-1] < 5.0


def test_bad_study_options_raise():
    with pytest.raises(ValueError, match="cells"):
        phymul.truthcube(cells=0)
    with pytest.raises(ValueError, match="probe must be"):
        phymul.prostate(probes=["laser"])
    with pytest.raises(ValueError, match="fillings"):
        phymul.prostate(fillings=[-1.0])
