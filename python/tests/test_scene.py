"""Scenes from Python: loaded and checked as by the program, edited with the schema's checks."""
import pytest

import phymul
from conftest import EXAMPLES, SOURCE, run_cli


def test_a_loaded_scene_reads_in_si_and_edits_with_units():
    scene = phymul.load_scene(str(EXAMPLES / "prostate" / "50mL_rigid.yaml"))
    assert scene.objects.keys() == ["prostate", "bladder"]
    prostate = scene.objects["prostate"]
    assert prostate.material.stiffness == 640.0
    assert prostate.material.density == 1050.0
    assert scene.simulation.damping == 20.0
    assert scene.simulation.gravity == (0.0, 0.0, -9.8100000000000005)
    assert scene.obstacles["probe"].radius == 0.01
    # 49.999999999999993 mL in the file, in m^3 here.
    assert scene.objects["bladder"].target_volume == [(0.0, pytest.approx(50e-6, rel=1e-15))]
    prostate.material.stiffness = 700
    assert scene.objects[0].material.stiffness == 700.0
    prostate.material.stiffness = "0.7 kN/m"
    assert prostate.material.stiffness == 700.0
    scene.objects["bladder"].target_volume = "100 mL"
    assert scene.objects["bladder"].target_volume == [(0.0, pytest.approx(1e-4, rel=1e-15))]
    scene.obstacles["probe"].motion = [(0, [0, 0, 0]), ("1 s", [0, 0, "2 mm"])]
    assert scene.obstacles["probe"].motion == [(0.0, (0.0, 0.0, 0.0)), (1.0, (0.0, 0.0, 0.002))]


def test_edits_out_of_range_or_of_the_wrong_type_are_refused_with_the_readers_message():
    scene = phymul.load_scene(str(EXAMPLES / "hanging_cube.yaml"))
    material = scene.objects["cube"].material
    with pytest.raises(ValueError, match=r"'stiffness' must be > 0 N/m \(got -5 N/m\)"):
        material.stiffness = -5
    with pytest.raises(ValueError, match="'stiffness' expects a stiffness"):
        material.stiffness = "5 mm"
    with pytest.raises(TypeError, match="'stiffness' expects a number"):
        material.stiffness = [1, 2]
    with pytest.raises(TypeError):
        material.stiffness = True
    with pytest.raises(ValueError, match="finite"):
        material.stiffness = float("nan")
    with pytest.raises(ValueError, match="'mode' must be one of dynamic, static"):
        scene.simulation.mode = "quasi"
    with pytest.raises(TypeError, match=r"three numbers"):
        scene.simulation.gravity = [0, 0]
    with pytest.raises(ValueError, match="strictly increasing"):
        scene.objects["cube"].target_volume = [(1.0, 1e-6), (0.5, 2e-6)]
    assert material.stiffness == 200.0  # nothing refused was written
    with pytest.raises(KeyError, match="known: cube"):
        scene.objects["liver"]
    with pytest.raises(IndexError):
        scene.objects[3]
    with pytest.raises(ValueError, match="did you mean 'stiffness'"):
        phymul.scene_field("material", "stifness")


# Each class of the module and the schema section its properties come from.
SECTIONS = {"Simulation": "simulation", "Output": "output", "Material": "material",
            "Mesh": "mesh", "Object": "object", "Obstacle": "obstacle", "Load": "load",
            "Pressure": "load", "Constraint": "constraint"}


def test_every_editable_property_is_a_schema_field_and_choices_read_back_as_written():
    scene = phymul.load_scene(str(EXAMPLES / "prostate" / "50mL_rigid.yaml"))
    holders = {"Simulation": scene.simulation, "Output": scene.output,
               "Material": scene.objects[0].material, "Mesh": scene.objects[0].mesh,
               "Object": scene.objects[0], "Obstacle": scene.obstacles[0]}
    seen = 0
    for name, section in SECTIONS.items():
        cls = getattr(phymul._phymul, name)
        for field, kind in cls.editable_fields.items():
            schema = phymul.scene_field(section, field)
            assert schema["doc"] in getattr(cls, field).__doc__
            seen += 1
            if kind != "choice" or name not in holders:
                continue
            for word in schema["choices"]:  # each word maps to its value and back
                setattr(holders[name], field, word)
                assert getattr(holders[name], field) == word
    assert seen > 50
    sim = scene.simulation
    sim.integrator = "newton-cotes"
    assert sim.integrator == "newton-cotes"
    with pytest.raises(ValueError, match="'integrator' must be one of verlet, newton-cotes, "
                                         "implicit"):
        sim.integrator = "rk4"
    with pytest.raises(AttributeError):
        scene.objects[0].mesh.generator = "box"  # what loading read stays as read


def test_a_bad_scene_raises_scene_error_with_the_lines_of_phymul_check():
    bad = SOURCE / "tests" / "data" / "bad_scenes"
    files = sorted(bad.glob("*.yaml"))
    assert len(files) >= 20
    for path in files:
        code, output = run_cli("check", path)
        assert code == 1, output
        with pytest.raises(phymul.SceneError) as caught:
            phymul.load_scene(str(path))
        assert caught.value.diagnostics, path
        for line in caught.value.diagnostics:
            assert line in output, (path, line, output)


def test_from_yaml_checks_text_and_names_it():
    with pytest.raises(phymul.SceneError) as caught:
        phymul.Scene.from_yaml("simulation: {dt: -1 ms}\nobjects: []\n", "mine.yaml")
    assert caught.value.diagnostics == [
        "mine.yaml:1:18: 'dt' must be > 0 s (got -0.001 s)",
        "mine.yaml:2:1: 'objects' needs at least 1 entry (got none)",
    ]
    text = (EXAMPLES / "hanging_cube.yaml").read_text()
    scene = phymul.Scene.from_yaml(text, str(EXAMPLES / "hanging_cube.yaml"))
    assert scene.objects["cube"].material.stiffness == 200.0


def test_a_copy_is_independent():
    scene = phymul.load_scene(str(EXAMPLES / "hanging_cube.yaml"))
    other = scene.copy()
    other.objects["cube"].material.stiffness = 400
    assert scene.objects["cube"].material.stiffness == 200.0
