"""phymul: soft organs simulated with the Phymul local shape memory model.

    scene = phymul.load_scene("scene.yaml")
    scene.objects["prostate"].material.stiffness = 700
    model = phymul.compile(scene)
    data = phymul.Data(model)
    phymul.step(model, data, n=100)
    data.positions  # (n, 3) float64, a view of the engine's memory

docs/python.md describes the whole API.
"""

import csv as _csv
import json as _json
import os as _os
import pathlib as _pathlib

import numpy as _np

from ._phymul import (  # noqa: F401
    CheckpointError,
    Data,
    InstabilityError,
    MeshFileError,
    Material,
    Mesh,
    Model,
    Obstacle,
    Object,
    Simulation,
    ResultWriter,
    Scene,
    SceneError,
    compile,
    component_volumes,
    forward,
    kinetic_energy,
    load_scene,
    read_mesh,
    scene_field,
    solve_static,
    step,
)
from . import _phymul
from .sweep import sweep  # noqa: F401 - parameter sweeps on Dask (docs/scale-out.md)

_DATA = _pathlib.Path(__file__).resolve().parent / "data"


def run(scene, out, progress=False, checkpoint_every=None, resume=False):
    """Runs a scene (a Scene or a scene file's path) as `phymul run` does, into `out`:
    frames, monitors.csv and report.json. Returns the report as a dict."""
    if isinstance(scene, (str, _os.PathLike)):
        scene = load_scene(str(scene))
    text = _phymul._run(scene, str(out), progress, checkpoint_every or "", resume)
    return _json.loads(text)


def read_report(directory):
    """A run's report.json as a dict."""
    with open(_pathlib.Path(directory) / "report.json", encoding="utf-8") as f:
        return _json.load(f)


def read_monitors(directory):
    """A run's monitors.csv as {column: float64 array}."""
    with open(_pathlib.Path(directory) / "monitors.csv", encoding="utf-8", newline="") as f:
        rows = list(_csv.reader(f))
    if not rows:
        raise ValueError(f"{directory}/monitors.csv is empty")
    header, body = rows[0], rows[1:]
    columns = _np.array(body, dtype=float).reshape(len(body), len(header))
    return {name: columns[:, k].copy() for k, name in enumerate(header)}


def truthcube(cells=8, fem=True, volume_constraint=True, young=14.9e3, poisson=0.499,
              beads=None):
    """The Truth Cube study: simulated beads against the measured ones, per compression level
    (shape memory, and the reference FEM when `fem`). Returns its table as a dict."""
    if not isinstance(cells, int) or not 2 <= cells <= 64:
        raise ValueError(f"cells must be a whole number in [2, 64] (got {cells!r})")
    if not 0.0 <= poisson <= 0.4999:
        raise ValueError(f"poisson must be in [0, 0.4999] (got {poisson!r})")
    path = str(beads) if beads is not None else str(_DATA / "truthcube" / "uniaxial_positions.csv")
    return _json.loads(_phymul._truthcube(cells, fem, volume_constraint, float(young),
                                          float(poisson), path))


def prostate(fillings=(50e-6, 100e-6, 200e-6, 300e-6, 400e-6), probes=("pressure", "rigid"),
             prostate_stiffness=640.0, coarse=False, out=None):
    """The prostate study (the paper's section 4): the probe's deformation of the prostate per
    bladder filling (m^3) and probe. Returns its table as a dict; with `out`, writes each
    equilibrium there too."""
    return _json.loads(_phymul._prostate([float(f) for f in fillings], list(probes),
                                         float(prostate_stiffness), bool(coarse),
                                         str(out) if out is not None else ""))
