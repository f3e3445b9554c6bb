#!/usr/bin/env python3
"""The installed package works for a program of one's own.

Installs the build (cmake --install) into a fresh prefix, builds examples/embed against it
with find_package(phymul), runs the embedding program and the installed `phymul run` on the
same scene, and compares the embedding program's final positions with the last frame of the
run, read back by meshio: the same bits. Also checks that no path of the source tree is
compiled into what is installed, and that the installed program finds its shared data.

usage: installed_package_test.py BUILD_DIR SOURCE_DIR WORK_DIR
"""
import os
import pathlib
import shutil
import subprocess
import sys

import meshio


def run(*args, **kwargs):
    result = subprocess.run(args, capture_output=True, text=True, **kwargs)
    if result.returncode != 0:
        sys.exit(f"{' '.join(map(str, args))} failed ({result.returncode}):\n"
                 f"{result.stdout}\n{result.stderr}")
    return result.stdout


def python_module(prefix, scene, points, env, sanitized):
    """The installed Python module, as /usr/bin/python3 imports it from the prefix's
    dist-packages, steps the scene to the program's last frame."""
    packages = list(prefix.glob("lib/python3*/dist-packages"))
    if not packages:
        if sanitized:  # the interpreter cannot load a sanitized module: none is built
            return
        sys.exit("the installation lacks the Python module (lib/python3.X/dist-packages)")
    script = (
        "import math, sys, phymul\n"
        "model = phymul.compile(phymul.load_scene(sys.argv[1]))\n"
        "data = phymul.Data(model)\n"
        "steps = math.ceil(model.duration / data.dt - 1e-9)\n"
        "data.dt = model.duration / steps\n"
        "phymul.step(model, data, n=steps)\n"
        "print(phymul.__file__)\n"
        "for x in data.positions: print(*(repr(float(v)) for v in x))\n")
    lines = run("/usr/bin/python3", "-c", script, scene,
                env=dict(env, PYTHONPATH=str(packages[0]))).splitlines()
    if not lines[0].startswith(str(prefix)):
        sys.exit(f"the Python module imported is not the installed one: {lines[0]}")
    stepped = [tuple(float(v) for v in line.split()) for line in lines[1:]]
    if stepped != [tuple(float(v) for v in p) for p in points]:
        sys.exit("the installed Python module does not end on phymul run's last frame")


def main():
    build, source, work = map(pathlib.Path, sys.argv[1:4])
    # A sanitized build's runtime records source paths (it is for tests, never installed).
    # --sanitized=COMPILER: the embedding program is built by that compiler with the
    # sanitizers' runtime, as the library was.
    sanitizer_compiler = next((a.split("=", 1)[1] for a in sys.argv[4:]
                               if a.startswith("--sanitized=")), None)
    sanitized = sanitizer_compiler is not None
    shutil.rmtree(work, ignore_errors=True)
    prefix = work / "prefix"
    run("cmake", "--install", build, "--prefix", prefix)
    for required in ("lib/libphymul.a", "lib/cmake/phymul/phymulConfig.cmake",
                     "include/phymul/phymul.hpp", "bin/phymul",
                     "share/phymul/data/truthcube/uniaxial_positions.csv",
                     "share/phymul/scripts/render.py"):
        if not (prefix / required).exists():
            sys.exit(f"the installation lacks {required}")

    # Nothing installed names the source tree (the program finds its data beside itself).
    needle = str(source.resolve()).encode()
    for path in prefix.rglob("*"):
        if not sanitized and path.is_file() and needle in path.read_bytes():
            sys.exit(f"{path.relative_to(prefix)} holds the source tree's path {needle.decode()}")

    embed = work / "embed"
    flags = [f"-DCMAKE_CXX_COMPILER={sanitizer_compiler}",
             "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined"] if sanitized else []
    run("cmake", "-S", source / "examples" / "embed", "-B", embed,
        f"-DCMAKE_PREFIX_PATH={prefix}", "-DCMAKE_BUILD_TYPE=Release", *flags)
    run("cmake", "--build", embed)

    scene = source / "examples" / "hanging_cube.yaml"
    env = dict(os.environ, OMP_NUM_THREADS="1")
    printed = run(embed / "embed", scene, env=env).splitlines()
    if not printed[0].startswith("t = 1.5"):
        sys.exit(f"the embedding program did not reach the scene's 1.5 s: {printed[0]}")
    positions = [tuple(float(v) for v in line.split()) for line in printed[1:]]

    out = work / "run"
    run(prefix / "bin" / "phymul", "run", "-q", scene, "-o", out, env=env)
    frames = sorted(out.glob("hanging_cube_*.vtu"))
    points = meshio.read(frames[-1]).points
    if len(points) != len(positions):
        sys.exit(f"{len(positions)} positions printed, {len(points)} in {frames[-1].name}")
    moved = 0.0
    for i, (printed_xyz, written) in enumerate(zip(positions, points)):
        if printed_xyz != tuple(float(v) for v in written):
            sys.exit(f"node {i}: the embedding program ends at {printed_xyz}, phymul run at "
                     f"{tuple(written)}")
        moved = max(moved, abs(written[2] - meshio.read(frames[0]).points[i][2]))
    if not moved > 1e-3:  # the cube hangs under gravity: it has sagged by millimetres
        sys.exit(f"the final frame is the rest shape (largest sag {moved} m)")

    # The installed program finds the measured beads beside itself.
    table = run(prefix / "bin" / "phymul", "truthcube", "--no-fem", "--no-pictures", "-o",
                work / "truthcube", env=env)
    if "18.25%" not in table:
        sys.exit(f"the installed truthcube study printed no table:\n{table}")
    python_module(prefix, scene, points, env, sanitized)
    print(f"installed to {prefix}; embed and phymul run agree on {len(points)} nodes, bit for "
          f"bit (largest sag {moved * 1e3:.3g} mm)")


if __name__ == "__main__":
    main()
