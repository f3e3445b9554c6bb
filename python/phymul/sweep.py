"""Parameter sweeps on Dask distributed: `phymul sweep sweep.yaml -o DIR`, `phymul.sweep(...)`.

A sweep file names a base scene (or the prostate study), the parameters it varies by path
(`objects[prostate].material.stiffness`), how their values combine (a grid, a list of cases, a
seeded random or Latin-hypercube sample) and the outputs to collect. Each sample runs as one
Dask task, on a local cluster or an existing one; DIR/results.csv gets one row per sample.
docs/scale-out.md is the reference. PyYAML, distributed, pandas and matplotlib are imported
only when a sweep is read or run, so that `import phymul` needs none of them.
"""

import contextlib
import copy
import csv
import ctypes
import difflib
import hashlib
import io
import itertools
import json
import math
import os
import pathlib
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import uuid

from . import _phymul

RESULTS = "results.csv"
# results.csv's own columns, around the parameters and outputs.
SAMPLE, STATUS, SAMPLE_TIME, WORKER, ERROR = "sample", "status", "sample_time_s", "worker", "error"
OWN_COLUMNS = (SAMPLE, STATUS, SAMPLE_TIME, WORKER, ERROR)
# Retries of a task that raised (a sample's own failure is a row, not an exception); a task
# whose worker died is rescheduled by Dask itself, up to distributed.scheduler.allowed-failures.
TASK_RETRIES = 2
INTERRUPTED = 130  # exit code, as `phymul run` and shells report a Ctrl-C
SAMPLES_FAILED = 2  # exit code: the sweep ran, some samples failed


class SweepError(_phymul.SceneError):
    """A bad sweep file; .diagnostics holds its "file:line:column: message" lines."""

    def __init__(self, diagnostics):
        self.diagnostics = list(diagnostics)
        super().__init__("\n".join(self.diagnostics))


def _need(module, package):
    try:
        return __import__(module, fromlist=["_"])
    except ImportError as e:
        raise ImportError(f"phymul sweeps need {module} ({e}); on Debian: apt-get install "
                          f"{package}") from e


# ---------------------------------------------------------------------------------------------
# The sweep file's YAML, every problem located at its node.

class _Reader:
    """YAML nodes of one sweep file; problems collect as "file:line:column: message"."""

    def __init__(self, name):
        self.name = name
        self.problems = []
        self._yaml = _need("yaml", "python3-yaml")
        self._constructor = self._yaml.constructor.SafeConstructor()

    def at(self, node):
        mark = node.start_mark
        return f"{self.name}:{mark.line + 1}:{mark.column + 1}"

    def problem(self, node, message):
        self.problems.append(f"{self.at(node)}: {message}")

    def compose(self, text):
        try:
            return self._yaml.compose(text)
        except self._yaml.YAMLError as e:
            mark = getattr(e, "problem_mark", None)
            where = f"{self.name}:{mark.line + 1}:{mark.column + 1}" if mark else self.name
            raise SweepError([f"{where}: not valid YAML: {getattr(e, 'problem', e)}"]) from None

    def value(self, node):
        return self._constructor.construct_object(node, deep=True)

    def is_mapping(self, node):
        return isinstance(node, self._yaml.MappingNode)

    def is_sequence(self, node):
        return isinstance(node, self._yaml.SequenceNode)

    def is_scalar(self, node):
        return isinstance(node, self._yaml.ScalarNode)

    def mapping(self, node, what, known, required=()):
        """{key: (key node, value node)} of a map, unknown and missing keys reported."""
        if not self.is_mapping(node):
            self.problem(node, f"{what} must be a map")
            return None
        out = {}
        for key_node, value_node in node.value:
            key = str(self.value(key_node))
            if key in out:
                self.problem(key_node, f"'{key}' is given twice in {what}")
            elif known is not None and key not in known:
                self.problem(key_node, f"unknown key '{key}' in {what} (allowed: "
                             f"{', '.join(known)}){_suggest(key, known)}")
            else:
                out[key] = (key_node, value_node)
        for key in required:
            if key not in out:
                self.problem(node, f"{what} needs '{key}'")
        return out

    def sequence(self, node, what, allow_empty=False):
        if not self.is_sequence(node):
            self.problem(node, f"{what} must be a list")
            return None
        if not node.value and not allow_empty:
            self.problem(node, f"{what} is empty")
            return None
        return node.value

    def string(self, node, what):
        value = self.value(node) if self.is_scalar(node) else None
        if not isinstance(value, str) or not value:
            self.problem(node, f"{what} must be a text")
            return None
        return value

    def integer(self, node, what, low):
        value = self.value(node) if self.is_scalar(node) else None
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            self.problem(node, f"{what} must be a whole number >= {low} (got "
                         f"{node.value if self.is_scalar(node) else 'a ' + node.id})")
            return None
        return value


def _suggest(word, known):
    close = [k for k in known if word and word in k][:1] or difflib.get_close_matches(
        word, list(known), n=1)
    return f"; did you mean '{close[0]}'?" if close else ""


def _shown(value):
    """A value as results.csv and messages show it."""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return json.dumps(value)
    return str(value)


# ---------------------------------------------------------------------------------------------
# Scene parameters: a path resolves to a field of a phymul.Scene (which checks units and ranges
# exactly as a scene file does) and to the key of the scene's YAML that holds it.

# What a sweep can vary, as the module binds it from the scene schema: each section's editable
# fields of the kinds a sweep writes.
_SWEEP_KINDS = ("quantity", "optional", "integer", "flag", "choice", "vector",
                "scalar_schedule", "vector_schedule")
_KINDS_BY_SECTION = {
    section: {name: kind for name, kind in cls.editable_fields.items() if kind in _SWEEP_KINDS}
    for section, cls in (("simulation", _phymul.Simulation), ("output", _phymul.Output),
                         ("material", _phymul.Material), ("mesh", _phymul.Mesh),
                         ("object", _phymul.Object), ("obstacle", _phymul.Obstacle))}
# Python attribute -> (schema section, YAML key, YAML keys it replaces, kind).
_LOAD_FIELDS = {
    "pressure": ("load", "pressure_schedule", ("pressure",), "scalar_schedule"),
    "force": ("load", "schedule", ("force",), "vector_schedule"),
}
_CONSTRAINT_FIELDS = {"displacement": ("constraint", "schedule", ("displacement",),
                                       "vector_schedule")}
# Setting K drops the Young's modulus it would be calibrated from (as phymul.Material does),
# and the other way round.
_REPLACES = {("material", "stiffness"): ("young", "poisson", "calibration_axis"),
             ("material", "young"): ("stiffness",)}
_LISTS = ("objects", "loads", "pressures", "constraints", "obstacles")
_SECTIONS = ("simulation", "output") + _LISTS


class _PathError(Exception):
    pass


class _Field:
    """One editable scene field: set and read on a phymul.Scene, written into its YAML."""

    def __init__(self, path, kind, section, name, locate, entry, key, replaces=(), event=None):
        self.path, self.kind, self.section, self.name = path, kind, section, name
        self._locate, self._entry, self._key = locate, entry, key
        self._replaces, self.event = replaces, event

    @property
    def unit(self):
        schema = self.name if self.section not in ("load", "constraint") else self._key
        try:
            return _phymul.scene_field(self.section, schema)["unit"]
        except Exception:  # a field the schema lists under another name: no unit on the plot
            return ""

    @property
    def numeric(self):
        return self.kind in ("quantity", "optional", "integer") or (
            self.kind == "scalar_schedule" and self.event is not None)

    def events(self, scene):
        return getattr(self._locate(scene), self.name)

    def set(self, scene, value):
        holder = self._locate(scene)
        if self.event is None:
            setattr(holder, self.name, _python_value(self.kind, value))
            return
        events = list(getattr(holder, self.name))
        t, _ = events[self.event]
        scalar = self.kind == "scalar_schedule"
        events[self.event] = (t, value if scalar or isinstance(value, str) else tuple(value))
        setattr(holder, self.name, events)

    def get(self, scene):
        value = getattr(self._locate(scene), self.name)
        if self.event is not None:
            value = value[self.event][1]
        return list(value) if isinstance(value, tuple) else value

    def write(self, tree, scene):
        """The scene's value of this field (SI, as read back) into the YAML tree."""
        entry = self._entry(tree)
        for key in self._replaces:
            entry.pop(key, None)
        value = getattr(self._locate(scene), self.name)
        if value is None and self._key == "dt":
            entry["dt"] = "auto"
        elif value is None:
            entry.pop(self._key, None)
        else:
            entry[self._key] = _yaml_value(self.kind, value)


def _python_value(kind, value):
    """A sweep file's value as the phymul.Scene setter takes it."""
    if kind == "optional" and (value is None or value == "auto"):
        return None
    if kind in ("scalar_schedule", "vector_schedule") and isinstance(value, list) and value \
            and isinstance(value[0], (dict, list)):
        events = []
        for event in value:
            if isinstance(event, dict) and set(event) == {"t", "value"}:
                t, v = event["t"], event["value"]
            elif isinstance(event, list) and len(event) == 2:
                t, v = event
            else:
                raise TypeError("schedule events are {t: ..., value: ...} maps or [t, value] pairs")
            events.append((t, tuple(v) if isinstance(v, list) else v))
        return events
    return value


def _yaml_value(kind, value):
    if kind == "vector":
        return [float(x) for x in value]
    if kind in ("quantity", "optional"):
        return float(value)
    if kind == "scalar_schedule":
        return [{"t": float(t), "value": float(v)} for t, v in value]
    if kind == "vector_schedule":
        return [{"t": float(t), "value": [float(x) for x in v]} for t, v in value]
    return value


_PATH = re.compile(r"^(?P<section>[A-Za-z_]+)(?:\[(?P<key>[^\]]*)\])?"
                   r"(?P<fields>(?:\.[A-Za-z_]+)*)(?:\[(?P<event>-?\d+)\])?$")


def _resolve(path, tree, scene):
    """The _Field a parameter path names in this scene; _PathError says why not."""
    m = _PATH.match(path)
    if not m:
        raise _PathError(f"'{path}' is not a parameter path (e.g. "
                         "objects[prostate].material.stiffness, simulation.duration)")
    section, key = m["section"], m["key"]
    fields = [f for f in m["fields"].split(".") if f]
    event = int(m["event"]) if m["event"] is not None else None
    if section not in _SECTIONS:
        raise _PathError(f"unknown parameter path '{path}': '{section}' is not a section "
                         f"(known: {', '.join(_SECTIONS)}){_suggest(section, _SECTIONS)}")
    if (key is None) != (section in ("simulation", "output")):
        form = f"{section}[name or index]" if section in _LISTS else section
        raise _PathError(f"'{path}': write {form}.field")
    if section in ("simulation", "output"):
        field = _section_field(path, section, fields, event)
    else:
        field = _list_field(path, section, key, fields, event, tree or {})
    if event is not None:
        _check_event(field, scene)
    return field


def _field_name(path, fields, known, what):
    if len(fields) != 1 or fields[0] not in known:
        name = ".".join(fields) or "(nothing)"
        raise _PathError(f"unknown parameter path '{path}': '{name}' is not {what} you can vary "
                         f"(known: {', '.join(known)}){_suggest(name, known)}")
    return fields[0]


def _section_field(path, section, fields, event):
    kinds = _KINDS_BY_SECTION[section]
    name = _field_name(path, fields, kinds, f"a field of {section}")
    return _Field(path, kinds[name], section, name, lambda s: getattr(s, section),
                  lambda tree: tree.setdefault(section, {}), name, event=event)


def _entries(tree, section):
    """(YAML index, entry) of a list section: loads and pressures are both YAML `loads`."""
    entries = list(enumerate(tree.get("loads" if section == "pressures" else section) or []))
    if section == "pressures":
        entries = [(j, e) for j, e in entries
                   if isinstance(e, dict) and e.get("type") == "pressure"]
    return [(j, e) for j, e in entries if isinstance(e, dict)]


def _entry_key(section, j, entry):
    if section == "objects":
        return str(entry.get("name"))
    if section == "obstacles":
        return str(entry.get("name", f"obstacle{j}"))
    return str(entry.get("object"))


def _find_entry(path, section, key, tree):
    """The YAML index of the entry `section[key]`, by name (or object) or by position."""
    entries = _entries(tree, section)
    if re.fullmatch(r"-?\d+", key.strip()):
        k = int(key)
        if not -len(entries) <= k < len(entries):
            raise _PathError(f"unknown parameter path '{path}': {section} has {len(entries)} "
                             f"entries (index 0 to {len(entries) - 1})")
        return entries[k][0]
    found = [j for j, e in entries if _entry_key(section, j, e) == key]
    names = list(dict.fromkeys(_entry_key(section, j, e) for j, e in entries))
    if not found:
        by = {"objects": "objects", "obstacles": "obstacles (by name)"}.get(
            section, f"{section} (by object)")
        raise _PathError(f"unknown parameter path '{path}' (known {by}: "
                         f"{', '.join(names) or 'none'}){_suggest(key, names)}")
    if len(found) > 1:
        raise _PathError(f"'{path}': {section}[{key}] names {len(found)} entries: index them by "
                         f"position instead ({section}[0] to {section}[{len(entries) - 1}])")
    return found[0]


def _python_list(scene, section, j, tree):
    """The phymul.Scene item of YAML entry j: pressures and force loads are separate lists."""
    if section in ("loads", "pressures"):
        loads = tree.get("loads") or []
        kind = loads[j].get("type")
        rank = sum(1 for e in loads[:j] if isinstance(e, dict) and e.get("type") == kind)
        return (scene.pressures if kind == "pressure" else scene.loads)[rank]
    return getattr(scene, section)[j]


def _list_field(path, section, key, fields, event, tree):
    j = _find_entry(path, section, key, tree)
    yaml_section = "loads" if section == "pressures" else section
    item = lambda s: _python_list(s, section, j, tree)  # noqa: E731
    entry = lambda t: t[yaml_section][j]  # noqa: E731
    if section == "objects" and fields and fields[0] in ("material", "mesh"):
        part = fields[0]
        kinds = _KINDS_BY_SECTION[part]
        name = _field_name(path, fields[1:], kinds, f"a field of an object's {part}")
        return _Field(path, kinds[name], part, name, lambda s: getattr(item(s), part),
                      lambda t: entry(t).setdefault(part, {}), name,
                      _REPLACES.get((part, name), ()), event)
    if section in ("objects", "obstacles"):
        schema = "object" if section == "objects" else "obstacle"
        kinds = _KINDS_BY_SECTION[schema]
        name = _field_name(path, fields, kinds, f"a field of {section}[]")
        return _Field(path, kinds[name], schema, name, item, entry, name, event=event)
    table = _CONSTRAINT_FIELDS if section == "constraints" else _LOAD_FIELDS
    if section == "constraints" and tree["constraints"][j].get("type") != "displacement":
        raise _PathError(f"unknown parameter path '{path}': constraints[{key}] holds its nodes "
                         "fixed (only a displacement constraint has a displacement to vary)")
    if section in ("loads", "pressures"):
        kind = tree["loads"][j].get("type")
        table = {"pressure" if kind == "pressure" else "force":
                 _LOAD_FIELDS["pressure" if kind == "pressure" else "force"]}
    name = _field_name(path, fields, table, f"a field of this {section[:-1]}")
    schema, yaml_key, replaces, kind = table[name]
    return _Field(path, kind, schema, name, item, entry, yaml_key, replaces, event)


def _check_event(field, scene):
    if field.kind not in ("scalar_schedule", "vector_schedule"):
        raise _PathError(f"'{field.path}': only a schedule's events take [k] "
                         f"('{field.name}' is not a schedule)")
    n = len(field.events(scene))
    if n == 0:
        raise _PathError(f"'{field.path}': the scene gives this schedule no events to index: "
                         "vary the whole schedule instead")
    if not -n <= field.event < n:
        raise _PathError(f"'{field.path}': the schedule has {n} event(s): [k] takes "
                         f"{-n} to {n - 1}")


def _refusal_is_the_files_fault(error):
    """A value of the wrong kind (unit, type) is an error of the sweep file; a value of the
    right kind outside its allowed range only fails the samples that take it."""
    return isinstance(error, (TypeError, IndexError, KeyError)) or " expects " in str(error)


# ---------------------------------------------------------------------------------------------
# Study parameters: `study: prostate` runs `phymul prostate` for one filling and probe per sample.

# name -> (option, dimension, SI to the option's unit, allowed SI range).
_PROSTATE_PARAMETERS = {
    "stiffness": ("--stiffness", "stiffness", 1.0, (1e-3, 1e6)),
    "bladder_stiffness": ("--bladder-stiffness", "stiffness", 1.0, (1e-3, 1e6)),
    "filling": ("--fillings", "volume", 1e6, (5e-6, 1e-3)),
    "force": ("--force", "force", 1.0, (1e-3, 100.0)),
    "lift": ("--lift", "length", 1e3, (1e-5, 0.02)),
    "hexahedra": ("--hexahedra", "integer", 1, (2, 40)),
    "probe": ("--probe", "choice", ("pressure", "rigid"), None),
    "coarse": ("--coarse-bladder", "flag", None, None),
    "support": ("--support", "choice", ("lateral", "bladder"), None),
    "support_stiffness": ("--support-stiffness", "stiffness", 1.0, (1e-3, 1e6)),
    "stitch_radius": ("--stitch-radius", "length", 1e3, (1e-3, 0.02)),
    "static_solver": ("--static-solver", "choice", ("relaxation", "implicit"), None),
    "relaxation": ("--relaxation", "choice", ("fire", "kinetic"), None),
    "contact_tolerance": ("--contact-tolerance", "force", 1.0, (1e-12, 1e-2)),
}
_PROSTATE_DEFAULTS = {"filling": 50e-6, "probe": "pressure"}
_PROSTATE_FIGURES = ("prostate_deformation_pct", "centre_displacement_mm", "centre_lift_mm",
                     "probe_force_n", "pressure_resultant_n", "bladder_volume_ml",
                     "target_volume_ml", "prostate_height_mm", "neck_force_n", "contact_force_n",
                     "hold_force_n", "top_node_force_n", "stitched_nodes", "iterations")
_UNITS = {"stiffness": "N/m", "volume": "m^3", "force": "N", "length": "m"}
# A scratch scene whose fields parse quantities with the engine's own units.
_SCRATCH = ("objects:\n  - name: scratch\n    mesh: {generator: box}\n"
            "    material: {stiffness: 1, density: 1}\n    volume_constraint: true\n")


def _quantity(dimension, name, value):
    """SI value of a quantity ("2 N", "50 mL" or a number), parsed by the engine's units."""
    scene = _phymul.Scene.from_yaml(_SCRATCH, "scratch.yaml")
    obj = scene.objects[0]
    try:
        if dimension == "stiffness":
            obj.material.stiffness = value
            return obj.material.stiffness
        if dimension == "volume":
            obj.target_volume = value
            return obj.target_volume[0][1]
        if dimension == "force":
            scene.simulation.tolerance = value
            return scene.simulation.tolerance
        obj.mesh.radius = value
        return obj.mesh.radius
    except (ValueError, TypeError) as e:
        message = re.sub(r"^'\w+'", f"'{name}'", str(e))
        raise type(e)(message) from None


class _StudyField:
    """A parameter of `phymul prostate`, checked against the program's own ranges."""

    def __init__(self, path, name):
        self.path, self.name = path, name
        self.option, self.dimension, self.scale, self.range = _PROSTATE_PARAMETERS[name]
        self.event = None

    unit = property(lambda self: _UNITS.get(self.dimension, ""))
    numeric = property(lambda self: self.dimension not in ("choice", "flag"))

    def convert(self, value):
        """The SI value; TypeError for a value of the wrong kind, ValueError out of range."""
        if self.dimension == "flag":
            if not isinstance(value, bool):
                raise TypeError(f"'{self.name}' expects true or false")
            return value
        if self.dimension == "choice":
            if value not in self.scale:
                raise ValueError(f"'{self.name}' must be one of {', '.join(self.scale)} "
                                 f"(got '{value}')")
            return value
        if self.dimension == "integer":
            if isinstance(value, bool) or not isinstance(value, int):
                raise TypeError(f"'{self.name}' expects a whole number")
            si = value
        else:
            si = _quantity(self.dimension, self.name, value)
        low, high = self.range
        if not low <= si <= high:
            unit = f" {self.unit}" if self.unit else ""
            raise ValueError(f"'{self.name}' must be in [{low:g}, {high:g}]{unit} (got "
                             f"{si:g}{unit})")
        return si

    def arguments(self, si):
        if self.dimension == "flag":
            return [self.option] if si else []
        if self.dimension in ("choice", "integer"):
            return [self.option, str(si)]
        return [self.option, f"{si * self.scale:.15g}"]


# ---------------------------------------------------------------------------------------------
# The sweep: its parameters, their values, the outputs.

class _Value:
    """One value of a parameter: its SI form, or why the scene refuses it (its sample fails)."""

    def __init__(self, value, where, shown, refusal=None):
        self.value, self.where, self.shown, self.refusal = value, where, shown, refusal

    @property
    def error(self):
        """The refusal located in the sweep file, as the sample's row gives it."""
        return self.refusal and f"{self.where}: {self.refusal}"


class _Parameter:
    def __init__(self, path, where, field):
        self.path, self.where, self.field = path, where, field
        self.values = []  # _Value, for a grid or for random choice among them
        self.low = self.high = None  # SI range for sampling
        self.log = False


class _Output:
    def __init__(self, name, source, field, where, of="last"):
        self.name, self.source, self.field, self.where, self.of = name, source, field, where, of


class Sweep:
    """A checked sweep file: build it with read_sweep()."""

    def __init__(self, file, name):
        self.file, self.name = file, name
        self.kind = None  # "scene" or "study"
        self.scene_file = self.base = self.tree = None
        self.study_fixed = {}
        self.parameters = []
        self.cases = None  # list of [(parameter, _Value)] when the file lists cases
        self.sampling = None  # (method, samples, seed)
        self.outputs = []
        self.program = None
        self.text = ""


_TOP_KEYS = ("name", "scene", "study", "set", "parameters", "cases", "sampling", "outputs")


def read_sweep(source, file_name=None):
    """A checked Sweep from a sweep file's path, or from a dict (paths relative to the current
    directory). SweepError lists every problem found, located."""
    if isinstance(source, dict):  # as YAML text, so that its problems are located too
        yaml = _need("yaml", "python3-yaml")
        plain = json.loads(json.dumps(source, default=str))  # paths and the like as text
        text, name, base_dir = yaml.safe_dump(plain, sort_keys=False), file_name or "sweep", "."
    else:
        path = pathlib.Path(source)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as e:
            raise SweepError([f"{path}: cannot read the sweep file ({e.strerror})"]) from None
        name, base_dir = file_name or str(path), path.parent
    reader = _Reader(name)
    root = reader.compose(text)
    if root is None:
        raise SweepError([f"{name}:1:1: the sweep file is empty"])
    sweep = Sweep(name, pathlib.Path(name).stem)
    sweep.text = text
    top = reader.mapping(root, "the sweep", _TOP_KEYS)
    if top is not None:
        _read_top(reader, sweep, top, root, pathlib.Path(base_dir))
    if reader.problems:
        raise SweepError(sorted(reader.problems, key=_position))
    return sweep


def _position(problem):
    """(line, column) of a "file:line:column: message" line, for the problems in file order."""
    m = re.match(r".*?:(\d+):(\d+): ", problem)
    return (int(m[1]), int(m[2])) if m else (0, 0)


def _read_top(reader, sweep, top, root, base_dir):
    if "name" in top:
        sweep.name = reader.string(top["name"][1], "name") or sweep.name
    if ("scene" in top) == ("study" in top):
        reader.problem(root, "a sweep names either a base scene (scene: FILE) or a study "
                       "(study: prostate)")
        return
    if "scene" in top:
        if not _read_base_scene(reader, sweep, top["scene"][1], base_dir):
            return
    elif not _read_study(reader, sweep, top["study"][1]):
        return
    if "set" in top:
        _read_fixed(reader, sweep, top["set"][1])
    if ("parameters" in top) == ("cases" in top):
        reader.problem(root, "a sweep varies its parameters either as a grid or sample "
                       "(parameters: [...]) or as a list of cases (cases: [...])")
    elif "parameters" in top:
        sampling = top.get("sampling")
        if sampling:  # a bad one is reported; the ranges are still read as for sampling
            sweep.sampling = _read_sampling(reader, sampling[1]) or ("random", 1, 0)
        _read_parameters(reader, sweep, top["parameters"][1])
    else:
        if "sampling" in top:
            reader.problem(top["sampling"][0], "sampling applies to parameters, not to cases")
        _read_cases(reader, sweep, top["cases"][1])
    _read_outputs(reader, sweep, top.get("outputs"))


def _read_base_scene(reader, sweep, node, base_dir):
    file = reader.string(node, "scene")
    if file is None:
        return False
    path = (base_dir / file).resolve()
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        reader.problem(node, f"cannot read the base scene {path} ({e.strerror})")
        return False
    try:
        sweep.base = _phymul.load_scene(str(path))
    except (ValueError, RuntimeError, OSError) as e:  # SceneError, MeshFileError
        lines = getattr(e, "diagnostics", None) or [str(e)]
        reader.problem(node, f"the base scene {file} is not valid:\n  " + "\n  ".join(lines))
        return False
    yaml = _need("yaml", "python3-yaml")
    sweep.tree = yaml.safe_load(text)
    _absolute_mesh_files(sweep.tree, path.parent)
    sweep.kind, sweep.scene_file = "scene", path
    return True


def _absolute_mesh_files(tree, directory):
    """Mesh files as absolute paths: each sample's scene lives in its own directory."""
    for obj in tree.get("objects") or []:
        mesh = obj.get("mesh") if isinstance(obj, dict) else None
        if isinstance(mesh, dict) and isinstance(mesh.get("file"), str):
            mesh["file"] = str((directory / mesh["file"]).resolve())


def _read_study(reader, sweep, node):
    study = reader.string(node, "study")
    if study is None:
        return False
    if study != "prostate":
        reader.problem(node, f"unknown study '{study}' (known: prostate)")
        return False
    sweep.program = _program()
    if sweep.program is None:
        reader.problem(node, "the study runs the phymul program, which was not found (set "
                       "PHYMUL_PROGRAM to its path)")
        return False
    sweep.kind = "study"
    return True


def _program():
    """The phymul program: the one that started us, else beside this module (build tree or
    installation), else on PATH."""
    here = pathlib.Path(__file__).resolve().parent
    # build/python/phymul -> build/phymul; <prefix>/lib/python3.X/dist-packages/phymul ->
    # <prefix>/bin/phymul.
    candidates = [os.environ.get("PHYMUL_PROGRAM"), here.parents[1] / "phymul",
                  here.parents[3] / "bin" / "phymul" if len(here.parents) > 3 else None,
                  shutil.which("phymul")]
    for c in candidates:
        if c and os.path.isfile(c) and os.access(c, os.X_OK):
            return str(pathlib.Path(c).resolve())
    return None


def _field(reader, sweep, path, node):
    """The field a path names, or None (reported)."""
    if sweep.kind == "study":
        if path not in _PROSTATE_PARAMETERS:
            known = _PROSTATE_PARAMETERS
            reader.problem(node, f"unknown parameter '{path}' of the prostate study (known: "
                           f"{', '.join(known)}){_suggest(path, known)}")
            return None
        return _StudyField(path, path)
    try:
        return _resolve(path, sweep.tree, sweep.base)
    except _PathError as e:
        reader.problem(node, str(e))
        return None


def _check_value(reader, field, sweep, node):
    """The _Value of a value node for this field: a refusal of the wrong kind is reported
    (the file's fault), one out of range is kept for its samples to fail with."""
    raw = reader.value(node)
    where = reader.at(node)
    try:
        if isinstance(field, _StudyField):
            si = field.convert(raw)
        else:
            scene = sweep.base.copy()
            field.set(scene, raw)
            si = field.get(scene)
        return _Value(si, where, _shown(si))
    except (ValueError, TypeError, IndexError, KeyError) as e:
        message = f"{field.path} = {_shown(raw)}: {e}"
        if _refusal_is_the_files_fault(e):
            reader.problem(node, message)
            return None
        return _Value(raw, where, _shown(raw), message)


def _read_fixed(reader, sweep, node):
    """`set:` edits every sample takes; any refusal is the file's fault."""
    entries = reader.mapping(node, "set", None)
    for path, (key_node, value_node) in (entries or {}).items():
        field = _field(reader, sweep, path, key_node)
        if field is None:
            continue
        value = _check_value(reader, field, sweep, value_node)
        if value is None:
            continue
        if value.refusal:
            reader.problem(value_node, value.refusal)
        elif sweep.kind == "study":
            sweep.study_fixed[path] = (field, value.value)
        else:
            field.set(sweep.base, value.value)
            field.write(sweep.tree, sweep.base)


_SAMPLING_METHODS = ("random", "latin-hypercube")


def _read_sampling(reader, node):
    # The seed is required: resume finds the same samples only if every run draws them alike.
    entries = reader.mapping(node, "sampling", ("method", "samples", "seed"),
                             ("method", "samples", "seed")) or {}
    method = samples = seed = None
    if "method" in entries:
        method = reader.string(entries["method"][1], "sampling method")
        if method is not None and method not in _SAMPLING_METHODS:
            reader.problem(entries["method"][1], f"unknown sampling method '{method}' (allowed: "
                           f"{', '.join(_SAMPLING_METHODS)}){_suggest(method, _SAMPLING_METHODS)}")
            method = None
    if "samples" in entries:
        samples = reader.integer(entries["samples"][1], "samples", 1)
    if "seed" in entries:
        seed = reader.integer(entries["seed"][1], "seed", 0)
    return None if None in (method, samples, seed) else (method, samples, seed)


def _read_parameters(reader, sweep, node):
    paths = set()
    for item in reader.sequence(node, "parameters") or []:
        entries = reader.mapping(item, "a parameter", ("path", "values", "range"), ("path",))
        if not entries or "path" not in entries:
            continue
        path = reader.string(entries["path"][1], "path")
        if path in paths:
            reader.problem(entries["path"][1], f"parameter '{path}' is given twice")
            continue
        paths.add(path)
        field = _field(reader, sweep, path, entries["path"][1]) if path else None
        if field is None:
            continue
        parameter = _Parameter(path, reader.at(entries["path"][1]), field)
        if ("values" in entries) == ("range" in entries):
            reader.problem(item, f"parameter '{path}' needs either values: [...] or "
                           "range: {min, max" + ("}" if sweep.sampling else ", count}"))
            continue
        if "values" in entries:
            _read_values(reader, sweep, parameter, entries["values"][1])
        else:
            _read_range(reader, sweep, parameter, entries["range"][1])
        sweep.parameters.append(parameter)


def _read_values(reader, sweep, parameter, node):
    for value_node in reader.sequence(node, f"the list of values of '{parameter.path}'") or []:
        value = _check_value(reader, parameter.field, sweep, value_node)
        if value is not None:
            parameter.values.append(value)


def _read_range(reader, sweep, parameter, node):
    grid = sweep.sampling is None
    keys = ("min", "max", "count", "scale") if grid else ("min", "max", "scale")
    entries = reader.mapping(node, f"range of '{parameter.path}'", keys,
                             ("min", "max", "count") if grid else ("min", "max"))
    if not entries or not all(k in entries for k in ("min", "max")):
        return
    if not parameter.field.numeric:
        reader.problem(node, f"'{parameter.path}' is not a number: list its values instead")
        return
    ends = []
    for end in ("min", "max"):
        value = _check_value(reader, parameter.field, sweep, entries[end][1])
        if value is not None and value.refusal:  # an end out of bounds: the whole range is
            reader.problem(entries[end][1], value.refusal)
            value = None
        ends.append(value)
    scale = reader.string(entries["scale"][1], "scale") if "scale" in entries else "linear"
    if scale not in (None, "linear", "log"):
        reader.problem(entries["scale"][1], f"scale must be linear or log (got '{scale}')")
    count = reader.integer(entries["count"][1], "count", 1) if "count" in entries else None
    if None in ends or scale not in ("linear", "log"):
        return
    low, high = ends[0].value, ends[1].value
    if low > high:
        reader.problem(node, f"empty range for '{parameter.path}': min {ends[0].shown} > max "
                       f"{ends[1].shown}")
        return
    if scale == "log" and low <= 0:
        reader.problem(node, f"a log range needs min > 0 (got {ends[0].shown})")
        return
    parameter.low, parameter.high, parameter.log = low, high, scale == "log"
    if grid and count is not None:
        for x in _spaced(low, high, count, parameter.log):
            if parameter.field.kind == "integer":
                x = int(round(x))
            parameter.values.append(_Value(x, reader.at(node), _shown(x)))


def _spaced(low, high, count, log):
    if count == 1:
        return [low]
    if log:
        return [math.exp(math.log(low) + (math.log(high) - math.log(low)) * k / (count - 1))
                for k in range(count)]
    return [low + (high - low) * k / (count - 1) for k in range(count)]


def _read_cases(reader, sweep, node):
    by_path = {}
    sweep.cases = []
    for item in reader.sequence(node, "cases") or []:
        entries = reader.mapping(item, "a case", None)
        if entries is None:
            continue
        if not entries:
            reader.problem(item, "a case sets at least one parameter")
        case = []
        for path, (key_node, value_node) in entries.items():
            if path not in by_path:
                field = _field(reader, sweep, path, key_node)
                by_path[path] = field and _Parameter(path, reader.at(key_node), field)
                if by_path[path]:
                    sweep.parameters.append(by_path[path])
            if by_path[path]:
                value = _check_value(reader, by_path[path].field, sweep, value_node)
                if value is not None:
                    case.append((by_path[path], value))
        sweep.cases.append(case)


_REPORT_FIELDS = ("status", "message", "mode", "steps", "simulated_time_s", "wall_time_s",
                  "ns_per_node_per_step", "real_time_factor", "step_wall_time_s",
                  "stepping_real_time_factor", "dt_s", "stable_dt_s", "nodes", "threads",
                  "frames", "converged", "final_residual_force_N", "solver",
                  "newton_iterations", "load_steps", "load_steps_done", "support_reaction_N",
                  "applied_load_N")
_DEFAULT_OUTPUTS = {"scene": ("steps", "final_residual_force_N"),
                    "study": ("prostate_deformation_pct", "centre_displacement_mm",
                              "probe_force_n")}
_MONITOR_OF = ("last", "min", "max", "mean")


def _read_outputs(reader, sweep, entry):
    if sweep.kind is None:
        return
    if entry is None:
        source = "report" if sweep.kind == "scene" else "study"
        sweep.outputs = [_Output(n, source, n, sweep.file) for n in _DEFAULT_OUTPUTS[sweep.kind]]
        return
    for node in reader.sequence(entry[1], "outputs") or []:
        output = _read_output(reader, sweep, node)
        if output is None:
            continue
        taken = {o.name for o in sweep.outputs} | {p.path for p in sweep.parameters}
        if output.name in taken or output.name in OWN_COLUMNS:
            reader.problem(node, f"output name '{output.name}' is already a column of "
                           f"{RESULTS}: give it another with name:")
            continue
        sweep.outputs.append(output)
    _check_monitor_columns(reader, sweep)


def _read_output(reader, sweep, node):
    sources = ("report", "monitor") if sweep.kind == "scene" else ("study",)
    if reader.is_scalar(node):
        name = reader.string(node, "an output")
        entries = {sources[0]: (node, node)} if name else None
    else:
        entries = reader.mapping(node, "an output", sources + ("of", "name"))
    if not entries:
        return None
    given = [s for s in sources if s in entries]
    if len(given) != 1:
        reader.problem(node, f"an output names one of {', '.join(sources)}")
        return None
    source = given[0]
    value_node = entries[source][1]
    field = reader.string(value_node, source)
    if field is None:
        return None
    known = {"report": _REPORT_FIELDS, "study": _PROSTATE_FIGURES, "monitor": None}[source]
    if known is not None and field not in known:
        what = "report.json field" if source == "report" else "figure of the prostate study"
        reader.problem(value_node, f"unknown {what} '{field}' (known: {', '.join(known)})"
                       f"{_suggest(field, known)}")
        return None
    of = "last"
    if "of" in entries:
        of = reader.string(entries["of"][1], "of")
        if source != "monitor" or of not in _MONITOR_OF:
            reader.problem(entries["of"][1], f"of: takes {', '.join(_MONITOR_OF)}, for a "
                           f"monitor column (got '{of}')")
            return None
    default = field if of == "last" else f"{of}_{field}"
    name = reader.string(entries["name"][1], "name") if "name" in entries else default
    return name and _Output(name, source, field, reader.at(value_node), of)


def _check_monitor_columns(reader, sweep):
    """Monitor columns checked against the base scene's monitors.csv header."""
    wanted = [o for o in sweep.outputs if o.source == "monitor"]
    if not wanted:
        return
    try:
        columns = _monitor_columns(sweep.base)
    except Exception:  # the samples will say what is wrong with the scene
        return
    for o in wanted:
        if o.field not in columns:
            reader.problems.append(f"{o.where}: '{o.field}' is not a column of this scene's "
                                   f"monitors.csv (columns: {', '.join(columns)})"
                                   f"{_suggest(o.field, columns)}")


def _monitor_columns(scene):
    model = _phymul.compile(scene)
    with tempfile.TemporaryDirectory() as directory:
        data = _phymul.Data(model)
        writer = _phymul.ResultWriter(model, directory)
        writer.monitor(data)
        writer.finish(data)
        del writer
        with open(os.path.join(directory, "monitors.csv"), encoding="utf-8") as f:
            return f.readline().strip().split(",")


# ---------------------------------------------------------------------------------------------
# Samples: every combination of a grid, each case, or a seeded sample of the ranges.

def _combinations(sweep):
    """Each sample's [(parameter, _Value)], in a fixed order."""
    if sweep.cases is not None:
        return sweep.cases
    if sweep.sampling is None:
        return [list(zip(sweep.parameters, values))
                for values in itertools.product(*(p.values for p in sweep.parameters))]
    numpy = _need("numpy", "python3-numpy")
    method, samples, seed = sweep.sampling
    rng = numpy.random.default_rng(seed)
    columns = []
    for parameter in sweep.parameters:
        if method == "latin-hypercube":  # one sample in each of n equal strata, shuffled
            u = (rng.permutation(samples) + rng.random(samples)) / samples
        else:
            u = rng.random(samples)
        columns.append([_drawn(parameter, float(x)) for x in u])
    return [list(zip(sweep.parameters, values)) for values in zip(*columns)]


def _drawn(parameter, u):
    """The value at u in [0, 1) of a parameter's range, or of its list of values."""
    if parameter.values:
        return parameter.values[min(int(u * len(parameter.values)), len(parameter.values) - 1)]
    if parameter.log:
        x = math.exp(math.log(parameter.low) + u * (math.log(parameter.high) -
                                                     math.log(parameter.low)))
    else:
        x = parameter.low + u * (parameter.high - parameter.low)
    if parameter.field.kind == "integer":
        x = int(round(x))
    return _Value(x, parameter.where, _shown(x))


class _Sample:
    def __init__(self, index, values):
        self.index, self.values = index, values
        self.id = None
        self.task = None  # what the worker runs
        self.error = None  # why the scene refuses its values: it fails without running


def _plan(sweep, out):
    """The samples with their ids and tasks, in order."""
    samples = [_Sample(k, values) for k, values in enumerate(_combinations(sweep))]
    width = max(4, len(str(len(samples) - 1)))
    for s in samples:
        body = _scene_body(sweep, s) if sweep.kind == "scene" else _study_arguments(sweep, s)
        digest = hashlib.sha1(json.dumps(body).encode()).hexdigest()[:8]
        s.id = f"{s.index:0{width}d}-{digest}"
        if s.error is None:
            s.task = _task(sweep, s, body, out)
    return samples


def _refusals(sample):
    return [v.error for _, v in sample.values if v.error]


def _scene_body(sweep, sample):
    """The sample's scene as YAML text (or the values it refuses, as a record)."""
    errors = _refusals(sample)
    if errors:
        sample.error = "; ".join(errors)
        return [_shown(v.value) for _, v in sample.values]
    yaml = _need("yaml", "python3-yaml")
    scene, tree = sweep.base.copy(), copy.deepcopy(sweep.tree)
    for parameter, value in sample.values:
        parameter.field.set(scene, value.value)
        parameter.field.write(tree, scene)
    return yaml.safe_dump(tree, sort_keys=False, default_flow_style=None, width=100)


def _study_arguments(sweep, sample):
    errors = _refusals(sample)
    if errors:
        sample.error = "; ".join(errors)
        return [_shown(v.value) for _, v in sample.values]
    settings = {name: value for name, (_, value) in sweep.study_fixed.items()}
    settings.update({p.path: v.value for p, v in sample.values})
    arguments = []
    for name, value in {**_PROSTATE_DEFAULTS, **settings}.items():
        arguments += _StudyField(name, name).arguments(value)
    return arguments


def _task(sweep, sample, body, out):
    task = {"id": sample.id, "kind": sweep.kind,
            "dir": str((out / "samples" / sample.id).resolve()),
            "outputs": [(o.name, o.source, o.field, o.of) for o in sweep.outputs]}
    if sweep.kind == "scene":
        edits = "".join(f"#   {p.path} = {v.shown} {p.field.unit}".rstrip() + "\n"
                        for p, v in sample.values)
        task["scene"] = (f"# Sample {sample.id} of the sweep {sweep.file}: the scene\n"
                         f"# {sweep.scene_file} with (SI)\n{edits}") + body
    else:
        task["program"], task["arguments"] = sweep.program, body
    return task


# ---------------------------------------------------------------------------------------------
# On a worker: one sample, into its own directory, placed there whole.

def run_sample(task):
    """Runs one sample (a Dask task): its directory gets the scene, the run's files and
    result.json; returns its row (outputs, status, error). A failing sample returns a
    "failed" row: only a bug or a lost worker raises."""
    start = time.perf_counter()
    final = pathlib.Path(task["dir"])
    final.parent.mkdir(parents=True, exist_ok=True)
    partial = final.with_name(f".{final.name}.partial-{uuid.uuid4().hex[:8]}")
    partial.mkdir()
    row = {STATUS: "ok", ERROR: ""}
    try:
        runner = _run_scene if task["kind"] == "scene" else _run_study
        row.update(runner(task, partial, final))
    except _SampleFailed as e:
        row.update(e.outputs)
        row[STATUS], row[ERROR] = "failed", str(e)
    except Exception as e:  # noqa: BLE001 - any error of one sample is that sample's
        lines = getattr(e, "diagnostics", None)
        row[STATUS] = "failed"
        row[ERROR] = "; ".join(lines) if lines else f"{type(e).__name__}: {e}"
    row[ERROR] = row[ERROR].replace(str(partial), str(final))
    row[SAMPLE_TIME] = time.perf_counter() - start
    row[WORKER] = _worker_name()
    _write_atomically(partial / "result.json", json.dumps(row, indent=1) + "\n")
    _place(partial, final)
    return row


class _SampleFailed(Exception):
    def __init__(self, message, outputs=None):
        super().__init__(message)
        self.outputs = outputs or {}


def _one_openmp_thread():
    """Each sample on one core: a worker runs as many samples at once as it has threads, and
    the results are the same bit for bit whatever the thread count. OMP_NUM_THREADS comes too
    late once the runtime is loaded; omp_set_num_threads holds for this (the task's) thread."""
    for name in ("libgomp.so.1", "libomp.so.5", "libomp.so"):
        try:
            ctypes.CDLL(name, mode=os.RTLD_NOLOAD | os.RTLD_LAZY).omp_set_num_threads(1)
            return
        except (OSError, AttributeError):
            continue


def _run_scene(task, partial, final):
    import phymul  # the package (run, read_monitors), loaded with this module

    _one_openmp_thread()
    text = task["scene"]
    _write_atomically(partial / "scene.yaml", text)
    # The run reads its scene file back (checkpoints): the one in the partial directory.
    scene = _phymul.Scene.from_yaml(text, str(partial / "scene.yaml"))
    report = phymul.run(scene, partial)
    outputs = _scene_outputs(task["outputs"], report, partial)
    if report["status"] != "completed":
        raise _SampleFailed(f"{report['status']}: {report['message']}", outputs)
    return outputs


def _scene_outputs(outputs, report, directory):
    import phymul

    values, monitors = {}, None
    for name, source, field, of in outputs:
        if source == "report":
            values[name] = report.get(field)
            continue
        if monitors is None:
            monitors = phymul.read_monitors(directory)
        if field not in monitors:
            raise _SampleFailed(f"'{field}' is not a column of monitors.csv (columns: "
                                f"{', '.join(monitors)})", values)
        column = monitors[field]
        values[name] = float(column[-1] if of == "last" else getattr(column, of)())
    return values


def _run_study(task, partial, final):
    command = [task["program"], "prostate", *task["arguments"], "--no-real-time",
               "--no-pictures", "-q", "-o", str(partial)]
    shown = " ".join(command).replace(str(partial), str(final))
    _write_atomically(partial / "command.txt", shown + "\n")
    env = dict(os.environ, OMP_NUM_THREADS="1")
    r = subprocess.run(command, capture_output=True, text=True, env=env, check=False)
    _write_atomically(partial / "table.txt", r.stdout)
    if r.returncode != 0:
        message = r.stderr.strip().replace(str(partial), str(final))
        raise _SampleFailed(f"phymul prostate exited with {r.returncode}: {message}")
    with open(partial / "prostate.json", encoding="utf-8") as f:
        figures = json.load(f)["fillings"][0]
    return {name: figures.get(field) for name, _, field, _ in task["outputs"]}


def _worker_name():
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return "local"


def _write_atomically(path, text):
    path = pathlib.Path(path)
    temporary = path.with_name(f".{path.name}.tmp-{os.getpid()}-{uuid.uuid4().hex[:6]}")
    temporary.write_text(text, encoding="utf-8")
    os.replace(temporary, path)


def _place(partial, final):
    """The finished sample directory in place of any earlier attempt's, whole."""
    if final.exists():
        old = final.with_name(f".{final.name}.old-{uuid.uuid4().hex[:8]}")
        os.rename(final, old)
        os.rename(partial, final)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.rename(partial, final)


# ---------------------------------------------------------------------------------------------
# results.csv: one row per sample, rewritten whole and atomically as samples finish.

class _Results:
    def __init__(self, out, sweep, samples):
        self.path = out / RESULTS
        self.columns = ([SAMPLE] + [p.path for p in sweep.parameters] +
                        [o.name for o in sweep.outputs] + [STATUS, SAMPLE_TIME, WORKER, ERROR])
        self.rows = {}
        for s in samples:
            row = {SAMPLE: s.id, STATUS: "pending"}
            row.update({p.path: v.shown for p, v in s.values})
            self.rows[s.id] = row
        self._last_write = self._write_cost = 0.0

    def finished(self, out):
        """Ids of the samples an earlier run finished ok: from results.csv, else from their
        directory's result.json (a sample may finish after results.csv's last write)."""
        done = set()
        if self.path.exists():
            with open(self.path, encoding="utf-8", newline="") as f:
                for old in csv.DictReader(f):
                    if old.get(SAMPLE) in self.rows and old.get(STATUS) == "ok":
                        self.rows[old[SAMPLE]].update(
                            {k: v for k, v in old.items() if k in self.columns and v is not None})
                        done.add(old[SAMPLE])
        for sample_id, row in self.rows.items():
            result = out / "samples" / sample_id / "result.json"
            if sample_id not in done and result.exists():
                try:
                    saved = json.loads(result.read_text(encoding="utf-8"))
                except (OSError, ValueError):
                    continue
                if saved.get(STATUS) == "ok":
                    row.update({k: _shown(v) for k, v in saved.items() if k in self.columns})
                    done.add(sample_id)
        return done

    def record(self, sample_id, outcome):
        self.rows[sample_id].update({k: "" if v is None else _shown(v)
                                     for k, v in outcome.items() if k in self.columns})

    def write(self, force=False):
        """Writes results.csv, at most taking a twentieth of the time (many samples)."""
        now = time.monotonic()
        if not force and now - self._last_write < 20 * self._write_cost:
            return
        buffer = io.StringIO()
        writer = csv.DictWriter(buffer, self.columns, lineterminator="\n")
        writer.writeheader()
        writer.writerows(self.rows.values())
        _write_atomically(self.path, buffer.getvalue())
        self._last_write = time.monotonic()
        self._write_cost = self._last_write - now

    def count(self, status):
        return sum(1 for r in self.rows.values() if r[STATUS] == status)


# ---------------------------------------------------------------------------------------------
# Running: a Dask client on a local cluster or an existing scheduler.

class _Progress:
    """A line on stderr, redrawn as samples finish, when stderr is a terminal."""

    def __init__(self, total, enabled):
        self.total, self.enabled = total, enabled and sys.stderr.isatty()
        self.start = time.monotonic()
        self._drawn = 0.0

    def update(self, done, failed):
        if not self.enabled or (time.monotonic() - self._drawn < 0.1 and 0 < done < self.total):
            return
        elapsed = time.monotonic() - self.start
        left = f", ~{elapsed / done * (self.total - done):.0f} s left" if done else ""
        bar = "#" * int(24 * done / max(self.total, 1))
        sys.stderr.write(f"\rsweep [{bar:<24}] {done}/{self.total}"
                         f"{f' ({failed} failed)' if failed else ''}, {elapsed:.0f} s{left}  ")
        sys.stderr.flush()
        self._drawn = time.monotonic()

    def close(self):
        if self.enabled:
            sys.stderr.write("\r" + " " * 78 + "\r")
            sys.stderr.flush()


def _cores():
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


class _Cluster:
    """A Client on the scheduler named, else on a local cluster of `workers` processes bound
    to 127.0.0.1 (one thread each), closed on exit."""

    def __init__(self, scheduler, workers):
        self.scheduler, self.workers = scheduler, workers
        self.cluster = self.client = None

    def __enter__(self):
        import logging

        distributed = _need("distributed", "python3-distributed")
        if self.scheduler:
            # A scheduler's address, or the file `dask scheduler --scheduler-file` wrote.
            where = ({"scheduler_file": self.scheduler} if os.path.isfile(self.scheduler)
                     else {"address": self.scheduler})
            try:
                self.client = distributed.Client(**where, timeout="10s")
            except (OSError, ValueError, TypeError) as e:
                raise RuntimeError(f"cannot reach the Dask scheduler at {self.scheduler} ({e}); "
                                   "is `dask scheduler` running there?") from None
        else:
            # Every port on 127.0.0.1, the HTTP ones (dashboard, health) included: without an
            # address, a worker's binds every interface.
            self.cluster = distributed.LocalCluster(
                n_workers=self.workers or _cores(), threads_per_worker=1, processes=True,
                host="127.0.0.1", dashboard_address="127.0.0.1:0",
                worker_dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR)
            self.client = distributed.Client(self.cluster)
        _check_workers(self.client, self.scheduler)
        return self.client

    def __exit__(self, *exc):
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def _check_workers(client, scheduler):
    """Every worker must import this very module: say so now rather than in every row."""
    check = lambda: __import__("phymul").__file__  # noqa: E731 - pickled by value
    try:
        client.run(check)
    except Exception as e:  # noqa: BLE001 - whatever the worker raised
        raise RuntimeError(f"the Dask workers of {scheduler or 'the local cluster'} cannot import "
                           f"phymul ({type(e).__name__}: {e}); start them with PYTHONPATH set to "
                           "the directory holding the phymul module (docs/scale-out.md)") from None


def _run_tasks(client, samples, results, progress, stop_after):
    """Submits the samples' tasks and records each as it finishes; a lost worker's tasks are
    rescheduled by Dask, a task that still fails becomes a failed row."""
    distributed = _need("distributed", "python3-distributed")
    token = uuid.uuid4().hex[:8]
    keys = [f"phymul-sample-{s.id}-{token}" for s in samples]
    futures = client.map(run_sample, [s.task for s in samples], key=keys, retries=TASK_RETRIES,
                         pure=False)
    by_key = {f.key: s for f, s in zip(futures, samples)}
    finished = failed = 0
    progress.update(0, 0)
    try:
        for future in distributed.as_completed(futures):
            sample = by_key[future.key]
            try:
                outcome = future.result()
            except Exception as e:  # noqa: BLE001 - KilledWorker, a bug: this sample's row
                outcome = {STATUS: "failed", ERROR: f"{type(e).__name__}: {e}"}
            results.record(sample.id, outcome)
            results.write()
            finished += 1
            failed += outcome[STATUS] != "ok"
            progress.update(finished, failed)
            if stop_after and finished >= stop_after:  # tests: as if interrupted here
                raise KeyboardInterrupt
    except BaseException:
        client.cancel(futures)
        raise


def sweep(source, out, scheduler=None, workers=None, resume=False, progress=True, plot=True):
    """Runs a sweep (a sweep file's path, or its content as a dict) into `out`: results.csv,
    samples/<id>/ and summary.png; returns results.csv as a pandas DataFrame. On a local
    Dask cluster of `workers` processes (default: every core), or on the scheduler at
    `scheduler` ("tcp://host:8786"). With `resume`, samples finished ok are kept, not rerun.
    SweepError for a bad sweep file; a failing sample is a row with status "failed"."""
    return _sweep(source, out, scheduler, workers, resume, progress, plot)[0]


def _sweep(source, out, scheduler, workers, resume, progress, plot=True, stop_after=None):
    """sweep(), and its summary line."""
    pandas = _need("pandas", "python3-pandas")
    started = time.monotonic()
    spec = read_sweep(source)
    out = pathlib.Path(out)
    if scheduler and workers:
        raise ValueError("workers sizes the local cluster; a scheduler's cluster has its own")
    if (out / RESULTS).exists() and not resume:
        raise FileExistsError(f"{out / RESULTS} exists: resume (--resume) continues that sweep; "
                              "or choose another directory")
    samples = _plan(spec, out)
    results = _Results(out, spec, samples)
    kept = results.finished(out) if resume else set()
    for s in samples:
        if s.error is not None:
            results.record(s.id, {STATUS: "failed", ERROR: s.error, SAMPLE_TIME: 0.0})
    todo = [s for s in samples if s.task is not None and s.id not in kept]
    # The cluster first: a scheduler out of reach leaves the directory as it was.
    with _Cluster(scheduler, workers) if todo else contextlib.nullcontext() as client:
        out.mkdir(parents=True, exist_ok=True)
        _write_atomically(out / "sweep.yaml", spec.text)
        results.write(force=True)
        bar = _Progress(len(todo), progress)
        try:
            if todo:
                _run_tasks(client, todo, results, bar, stop_after)
            _remove_partials(out)  # only now: no task of ours runs any more
        finally:
            bar.close()
            results.write(force=True)
    picture = _summary_plot(out, spec, results) if plot else None
    line = _summary_line(spec, out, results, len(kept), time.monotonic() - started, picture)
    text_columns = {c: str for c in (SAMPLE, STATUS, WORKER, ERROR)}
    frame = pandas.read_csv(out / RESULTS, float_precision="round_trip", keep_default_na=False,
                            na_values=[""], dtype=text_columns)
    frame[[WORKER, ERROR]] = frame[[WORKER, ERROR]].fillna("")  # empty, not a missing number
    return frame, line


def _remove_partials(out):
    """Leftovers of attempts on a worker that died (a shared directory)."""
    samples = out / "samples"
    for leftover in samples.glob(".*.partial-*") if samples.exists() else []:
        shutil.rmtree(leftover, ignore_errors=True)


def _summary_line(spec, out, results, kept, seconds, plot):
    ok, failed = results.count("ok"), results.count("failed")
    before = f" ({kept} kept from before)" if kept else ""
    extra = f" and {plot}" if plot else ""
    return (f"{spec.file}: {len(results.rows)} samples, {ok} ok, {failed} failed{before} in "
            f"{seconds:.1f} s; results in {out / RESULTS}{extra}")


# ---------------------------------------------------------------------------------------------
# summary.png: each output against the varied parameters.

def _numbers(rows, column):
    """The column as numbers, or None (text, or a case that left it unset)."""
    try:
        return [float(r.get(column)) for r in rows]
    except (TypeError, ValueError):
        return None


def _summary_plot(out, spec, results):
    """One parameter: each output against it; two: one curve per value of the second; three:
    a panel per value of the third. Otherwise (or for random samples with many values) each
    output against each parameter, as points. None when there is nothing numeric to plot."""
    rows = [r for r in results.rows.values() if r[STATUS] == "ok"]
    outputs = [o.name for o in spec.outputs if rows and _numbers(rows, o.name)]
    varied = [p for p in spec.parameters if len({r.get(p.path, "") for r in rows}) > 1]
    varied.sort(key=lambda p: _numbers(rows, p.path) is None)  # numbers on the x axis first
    if not rows or not outputs or not varied:
        return None
    try:
        from matplotlib.figure import Figure
    except ImportError:
        return None
    x = varied[0]
    series = varied[1] if len(varied) > 1 else None
    panels = varied[2] if len(varied) > 2 else None
    distinct = lambda p: sorted({r.get(p.path, "") for r in rows}, key=_order)  # noqa: E731
    grid_like = len(varied) <= 3 and _numbers(rows, x.path) is not None and all(
        len(distinct(p)) <= 8 for p in varied[1:])
    panel_values = distinct(panels) if panels and grid_like else [None]
    # Outputs down, panels across; without panels, the outputs two by two.
    across = len(panel_values) if panels and grid_like else min(2, len(outputs))
    down = len(outputs) if panels and grid_like else -(-len(outputs) // across)
    figure = Figure(figsize=(4.4 * across, 3.1 * down), layout="constrained")
    axes = figure.subplots(down, across, squeeze=False).ravel()
    for ax in axes[len(outputs) * len(panel_values):]:
        ax.set_visible(False)
    for i, name in enumerate(outputs):
        for j, panel in enumerate(panel_values):
            subset = [r for r in rows if panel is None or r.get(panels.path) == panel]
            ax = axes[i * len(panel_values) + j]
            if grid_like:
                _draw_curves(ax, subset, x, series, name, distinct)
            else:
                _draw_points(ax, subset, varied, name)
            ax.set_ylabel(name)
            ax.grid(alpha=0.3)
            if panel is not None:
                ax.set_title(f"{panels.path} = {_label(panels, panel)}", fontsize=9)
    figure.suptitle(f"{spec.name}: {len(rows)} samples")
    path = out / "summary.png"
    temporary = out / f".summary.png.tmp-{os.getpid()}"
    figure.savefig(temporary, dpi=110, format="png")
    os.replace(temporary, path)
    return path


def _order(text):
    try:
        return (0, float(text), "")
    except ValueError:
        return (1, 0.0, text)


# Units the plots show instead of SI (a bladder's filling reads better in mL).
_SHOWN_UNITS = {"m^3": ("mL", 1e6), "m": ("mm", 1e3)}


def _shown_unit(parameter):
    unit = parameter.field.unit
    return _SHOWN_UNITS.get(unit, (unit, 1.0))


def _label(parameter, value):
    unit, scale = _shown_unit(parameter)
    try:
        return f"{float(value) * scale:.4g}" + (f" {unit}" if unit else "")
    except ValueError:
        return value


def _draw_curves(ax, rows, x, series, name, distinct):
    for value in distinct(series) if series else [None]:
        part = sorted((r for r in rows if series is None or r.get(series.path) == value),
                      key=lambda r: float(r[x.path]))
        label = f"{series.path} = {_label(series, value)}" if series else None
        unit, scale = _shown_unit(x)
        xs = [v * scale for v in _numbers(part, x.path)]
        ax.plot(xs, _numbers(part, name), "o-", label=label, markersize=4)
    if x.log:
        ax.set_xscale("log")
    ax.set_xlabel(f"{x.path}" + (f" [{unit}]" if unit else ""))
    if series:
        ax.legend(fontsize=7)


def _draw_points(ax, rows, varied, name):
    numeric = [p for p in varied if _numbers(rows, p.path) is not None]
    for p in numeric[:4]:  # each parameter scaled to [0, 1] on one axis
        xs = _numbers(rows, p.path)
        low, high = min(xs), max(xs)
        span = (high - low) or 1.0
        ax.plot([(v - low) / span for v in xs], _numbers(rows, name), ".", label=p.path)
    ax.set_xlabel("parameter, from its smallest (0) to its largest (1) value")
    ax.legend(fontsize=7)


# ---------------------------------------------------------------------------------------------
# The command: `phymul sweep` runs `python3 -m phymul sweep`.

def main(argv=None):
    import argparse

    parser = argparse.ArgumentParser(
        prog="phymul sweep", description="Runs a parameter sweep on Dask (docs/scale-out.md).")
    parser.add_argument("sweep", help="sweep file (YAML)")
    parser.add_argument("-o", "--output", required=True, help="output directory")
    parser.add_argument("--scheduler", help="an existing Dask scheduler: tcp://HOST:PORT, or the "
                        "file `dask scheduler --scheduler-file` wrote")
    parser.add_argument("--workers", type=int, help="local cluster: worker processes "
                        "(default: every core)")
    parser.add_argument("--resume", action="store_true",
                        help="continue the sweep in the output directory: samples finished ok "
                             "are kept")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress line")
    parser.add_argument("--stop-after", type=int, help=argparse.SUPPRESS)  # tests: interrupt
    args = parser.parse_args(argv)
    if args.workers is not None and not 1 <= args.workers <= 4096:
        parser.error(f"--workers must be in [1, 4096] (got {args.workers})")
    # A batch system's SIGTERM (Slurm at its time limit) stops the sweep as Ctrl-C does.
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    try:
        frame, line = _sweep(args.sweep, args.output, args.scheduler, args.workers, args.resume,
                             not args.quiet, stop_after=args.stop_after)
    except SweepError as e:
        for problem in e.diagnostics:
            print(problem, file=sys.stderr)
        print(f"{len(e.diagnostics)} problem(s) found", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{args.sweep}: interrupted; what finished is in {args.output}/{RESULTS}; "
              f"--resume continues the sweep", file=sys.stderr)
        return INTERRUPTED
    except (OSError, RuntimeError, ValueError, ImportError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    print(line)
    failed = frame[frame[STATUS] != "ok"]
    for _, row in failed.head(5).iterrows():
        print(f"sample {row[SAMPLE]} failed: {row[ERROR]}", file=sys.stderr)
    if len(failed) > 5:
        print(f"... and {len(failed) - 5} more (results.csv, column error)", file=sys.stderr)
    return SAMPLES_FAILED if len(failed) else 0
