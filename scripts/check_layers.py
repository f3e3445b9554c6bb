#!/usr/bin/env python3
"""Fails when an include goes up the stack (docs/model.md, "Library architecture").

Layers, lowest first: mesh < fem < model < forces, constraints < solver < io < studies <
apps, python. A source file may include its own layer and those below. Files under src/<layer>/
belong to that layer, a public header include/phymul/<name>.hpp to the layer PUBLIC names,
include/phymul/studies/ to the studies.
Usage: check_layers.py [ROOT] (ROOT: the source tree, by default this script's).
Prints every offending include as file:line and exits 1; exits 0 when there is none.
"""
import pathlib
import re
import sys

ORDER = ["mesh", "fem", "model", "forces", "constraints", "solver", "io", "studies", "apps"]
RANK = {"mesh": 0, "fem": 1, "model": 2, "forces": 3, "constraints": 3, "solver": 4, "io": 5,
        "studies": 6, "apps": 7, "python": 7}
# The layer of each public header (include/phymul/<name>.hpp).
PUBLIC = {
    "phymul.hpp": "io",  # the umbrella header: the library, studies aside
    "mesh.hpp": "mesh",
    "meshing.hpp": "mesh",
    "label_surface.hpp": "mesh",
    "schedule.hpp": "mesh",
    "fem.hpp": "fem",
    "scene.hpp": "model",
    "scene_words.hpp": "model",
    "model.hpp": "model",
    "data.hpp": "model",
    "forces.hpp": "forces",
    "simulation.hpp": "solver",
    "calibration.hpp": "solver",
    "mesh_io.hpp": "io",
    "nifti.hpp": "io",
    "schema.hpp": "io",
    "vtk.hpp": "io",
    "results.hpp": "io",
    "run.hpp": "io",
    "scene_io.hpp": "io",
    "checkpoint.hpp": "io",
    "installation.hpp": "io",
    "camitk.hpp": "io",
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def layer_of(root, path):
    rel = path.relative_to(root).parts
    if rel[0] == "src" and len(rel) > 2:
        return rel[1]
    if rel[0] == "include" and rel[1] == "phymul":
        return "studies" if rel[2] == "studies" else PUBLIC.get(rel[2])
    if rel[0] == "apps":
        return "apps"
    if rel[0] == "python":
        return "python"
    return None


def target_layer(root, including, name):
    """The layer of an included file, looked up as the build's include paths do."""
    for base in (including.parent, root / "src", root / "include"):
        candidate = base / name
        if candidate.is_file():
            return layer_of(root, candidate.resolve()), candidate
    return None, None


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else __file__).resolve()
    if len(sys.argv) <= 1:
        root = root.parent.parent
    problems, unknown = [], []
    files = [p for d in ("src", "include", "apps", "python") if (root / d).is_dir()
             for p in (root / d).rglob("*") if p.suffix in (".cpp", ".hpp", ".h")]
    for path in sorted(files):
        mine = layer_of(root, path)
        if mine is None:
            unknown.append(f"{path.relative_to(root)}: in no layer (add it to PUBLIC or a layer folder)")
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            match = INCLUDE.match(line)
            if not match:
                continue
            theirs, found = target_layer(root, path, match.group(1))
            if found is None or theirs is None:
                continue
            if RANK[theirs] > RANK[mine]:
                problems.append(f"{path.relative_to(root)}:{number}: the {mine} layer includes "
                                f"\"{match.group(1)}\" of the {theirs} layer above it")
    for line in unknown + problems:
        print(line)
    if unknown or problems:
        print(f"{len(problems)} include(s) up the stack, {len(unknown)} file(s) in no layer; "
              f"layers, lowest first: mesh < fem < model < forces, constraints < solver < io < "
              f"studies < apps, python", file=sys.stderr)
        return 1
    print(f"layers: {len(files)} files, every include goes down the stack or stays level")
    return 0


if __name__ == "__main__":
    sys.exit(main())
