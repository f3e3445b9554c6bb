"""A controller acting between steps: applied forces, an obstacle's or an instrument's pose,
a pressure, a target volume, each set from Python for one Data."""
import numpy as np
import pytest

import phymul
from conftest import EXAMPLES


def load(name):
    return phymul.load_scene(str(EXAMPLES / name))


def test_applied_forces_equal_to_gravity_give_the_gravity_run_bit_for_bit():
    with_gravity = phymul.compile(load("hanging_cube.yaml"))
    scene = load("hanging_cube.yaml")
    scene.simulation.gravity = [0, 0, 0]
    without = phymul.compile(scene)
    a, b = phymul.Data(with_gravity), phymul.Data(without)
    b.applied_forces[:, 2] = without.masses * -9.81  # m g on every node, from Python
    phymul.forward(without, b)  # the forces now, for the first half kick
    phymul.step(with_gravity, a, n=400)
    phymul.step(without, b, n=400)
    assert np.array_equal(a.positions, b.positions)
    assert np.max(np.abs(b.positions - without.rest_positions)) > 1e-4  # it did sag


def test_applied_forces_change_the_momentum_by_their_impulse():
    text = (EXAMPLES / "hanging_cube.yaml").read_text()
    free = text.replace("constraints:\n  - {type: fixed, object: cube, nodes: top}\n", "")
    free = free.replace("gravity: [0, 0, -9.81 m/s^2]", "gravity: [0, 0, 0]")
    free = free.replace("damping: 6 1/s", "damping: 0 1/s")
    model = phymul.compile(phymul.Scene.from_yaml(free, str(EXAMPLES / "free_cube.yaml")))
    data = phymul.Data(model)
    f = np.zeros((model.nodes, 3))
    f[0] = [0.02, -0.01, 0.005]  # N on one corner only
    data.applied_forces[:] = f
    phymul.forward(model, data)
    phymul.step(model, data, n=250)
    momentum = (model.masses[:, None] * data.velocities).sum(axis=0)
    # The shape memory's reaction keeps momentum: only the applied force changes it.
    np.testing.assert_allclose(momentum, f[0] * data.time, rtol=1e-9)


def test_moving_the_probe_from_python_as_its_schedule_did_gives_the_same_run():
    scheduled = phymul.compile(load("probe.yaml"))
    scene = load("probe.yaml")
    scene.obstacles["probe"].motion = [0, 0, 0]  # the program drives it now
    driven = phymul.compile(scene)
    a, b = phymul.Data(scheduled), phymul.Data(driven)
    b.dt = a.dt

    def push(model, data):  # the scene's 8 mm over 0.6 s, then held
        t = data.time + data.dt
        data.move_obstacle("probe", [0.0, 0.0, t / 0.6 * 0.008 if t < 0.6 else 0.008])

    b.controller = push
    phymul.step(scheduled, a, n=300)
    phymul.step(driven, b, n=300)
    assert np.array_equal(a.positions, b.positions)
    assert np.array_equal(a.obstacle_forces, b.obstacle_forces)
    assert b.obstacle_translation("probe")[2] == a.obstacle_translation(0)[2] > 1e-3
    assert a.obstacle_forces[0, 2] > 0.0  # the probe pushes the block up


def test_driving_an_instrument_from_python_as_its_schedule_did_gives_the_same_run():
    scheduled = phymul.compile(load("fig1b_doubled_nodes.yaml"))
    a, b = phymul.Data(scheduled), phymul.Data(scheduled)

    def turn(model, data):  # the bone's rotation schedule: -0.5236 rad about y over 1 s
        t = data.time + data.dt
        data.move_body("bone", [0, 0, 0], [0.0, t / 1.0 * -0.5236 if t < 1.0 else -0.5236, 0.0])

    b.controller = turn
    phymul.step(scheduled, a, n=200)
    phymul.step(scheduled, b, n=200)
    assert np.array_equal(a.positions, b.positions)
    b.controller = lambda m, d: d.move_body("bone", [0, 0, 0.01], [0, 0, 0])
    phymul.step(scheduled, b, n=1)
    bone = scheduled.components["bone"]["nodes"]
    np.testing.assert_allclose(b.positions[bone], scheduled.rest_positions[bone] + [0, 0, 0.01],
                               atol=1e-15)


def test_setting_the_pressure_from_python_as_its_schedule_did_gives_the_same_run():
    model = phymul.compile(load("pressure_probe.yaml"))
    a, b = phymul.Data(model), phymul.Data(model)

    def press(m, d):
        t = d.time + d.dt
        d.set_pressure("prostate", t / 0.6 * 300.0 if t < 0.6 else 300.0)

    b.controller = press
    phymul.step(model, a, n=300)
    phymul.step(model, b, n=300)
    assert np.array_equal(a.positions, b.positions)
    assert b.pressure(0) == a.pressure("prostate") > 0.0
    b.controller = None
    b.set_pressure(0, 0.0)  # released: the prostate springs back toward rest
    before = np.abs(b.positions - model.rest_positions).max()
    phymul.step(model, b, n=1500)
    assert np.abs(b.positions - model.rest_positions).max() < 0.5 * before


def test_a_new_target_volume_is_reached_exactly():
    model = phymul.compile(load("balloon.yaml"))
    data = phymul.Data(model)
    rest = phymul.component_volumes(model, data)[0]
    assert data.target_volume("balloon") == pytest.approx(rest, rel=1e-12)
    data.set_target_volume("balloon", 1.2 * rest)
    phymul.step(model, data, n=50)
    volume = phymul.component_volumes(model, data)[0]
    assert volume == pytest.approx(1.2 * rest, rel=1e-10)


def test_controls_refuse_wrong_names_values_and_free_bodies():
    model = phymul.compile(load("probe.yaml"))
    data = phymul.Data(model)
    with pytest.raises(KeyError, match="known: probe"):
        data.move_obstacle("needle", [0, 0, 0])
    with pytest.raises(IndexError):
        data.move_obstacle(3, [0, 0, 0])
    with pytest.raises(ValueError, match="three numbers"):
        data.move_obstacle("probe", [0, 0])
    with pytest.raises(ValueError, match="finite"):
        data.move_obstacle("probe", [0, float("nan"), 0])
    with pytest.raises(KeyError, match="known: none"):
        data.set_pressure("tissue", 10.0)
    with pytest.raises(ValueError, match="> 0 m"):
        data.set_target_volume("tissue", -1.0)
    muscle = phymul.compile(load("fig1c_ligament.yaml"))
    d = phymul.Data(muscle)
    d.move_body("upper_bone", [0, 0, 0])  # driven (motion: {}): allowed
    with pytest.raises(ValueError, match="is free"):
        d.move_body("lower_bone", [0, 0, 0])
    forces = data.applied_forces
    with pytest.raises(ValueError):
        forces[:] = np.zeros((2, 3))
