"""Data from Python: NumPy views of the engine's memory, writes that move nodes, lifetimes."""
import gc

import numpy as np
import pytest

import phymul
from conftest import EXAMPLES


def cube(gravity=True):
    scene = phymul.load_scene(str(EXAMPLES / "hanging_cube.yaml"))
    if not gravity:
        scene.simulation.gravity = [0, 0, 0]
    model = phymul.compile(scene)
    return model, phymul.Data(model)


def test_arrays_view_the_engines_memory_without_copying():
    model, data = cube()
    x, v, f = data.positions, data.velocities, data.forces
    assert x.shape == (model.nodes, 3) and x.dtype == np.float64
    assert x.flags.writeable and v.flags.writeable and not f.flags.writeable
    assert not x.flags.owndata
    # At rest (the position constraints, applied once, move nodes by rounding only).
    np.testing.assert_allclose(x, model.rest_positions, rtol=0, atol=1e-15)
    phymul.step(model, data, n=5)
    # The same array object shows the positions after the steps: it views, not copies.
    assert data.steps == 5 and data.time == pytest.approx(5 * data.dt, rel=1e-12)
    assert np.shares_memory(x, data.positions)
    assert not np.array_equal(x, model.rest_positions)
    # Hanging under gravity: the free nodes move down, the fixed top stays.
    top = model.components["cube"]["node_sets"]["top"]
    np.testing.assert_array_equal(x[top], model.rest_positions[top])
    free = np.setdiff1d(np.arange(model.nodes), top)
    assert np.all(v[free, 2] < 0.0)


def test_writing_positions_moves_the_nodes_and_the_forces_pull_them_back():
    model, data = cube(gravity=False)
    np.testing.assert_allclose(data.forces, 0.0, atol=1e-12)  # at rest, no load
    bottom = model.components["cube"]["node_sets"]["bottom"]
    k = int(bottom[len(bottom) // 2])  # the middle of the free bottom face
    data.positions[k, 2] -= 1e-3  # pulled 1 mm down
    phymul.forward(model, data)
    assert data.forces[k, 2] > 0.0  # the shape memory pulls it back up
    assert abs(data.forces[k, 2]) > 100 * max(abs(data.forces[k, 0]), abs(data.forces[k, 1]))
    before = data.positions[k, 2]
    phymul.step(model, data, n=20)
    assert data.positions[k, 2] > before  # and the node moves back toward its rest place


def test_arrays_keep_their_data_alive():
    model, data = cube()
    phymul.step(model, data, n=3)
    x = data.positions
    expected = x.copy()
    comps = model.components["cube"]
    del data, model
    gc.collect()
    np.testing.assert_array_equal(x, expected)
    x += 1.0  # still the engine's memory, still writable
    assert comps["nodes"].shape[0] == x.shape[0]
    assert comps["surface"].shape[1] == 3 and comps["surface"].max() < x.shape[0]


def test_components_give_node_sets_ranges_and_surfaces_as_index_arrays():
    model, _ = cube()
    c = model.components["cube"]
    assert c["kind"] == "elastic"
    assert c["nodes"].dtype == np.int32 and c["nodes"].shape == (343,)  # 7^3 nodes
    assert len(c["surface"]) == 6 * 6 * 6 * 2  # two triangles per boundary quad
    assert sorted(c["node_sets"]) == ["back", "bottom", "front", "left", "right", "top"]
    top = c["node_sets"]["top"]
    assert np.all(model.rest_positions[top, 2] == model.rest_positions[:, 2].max())
    with pytest.raises(ValueError):
        c["nodes"][0] = 3  # read-only


def test_wrong_calls_raise_and_never_crash():
    model, data = cube()
    other = phymul.compile(phymul.load_scene(str(EXAMPLES / "hanging_cube.yaml")))
    with pytest.raises(ValueError, match="another Model"):
        phymul.step(other, data)
    with pytest.raises(ValueError, match="n must be >= 0"):
        phymul.step(model, data, n=-1)
    with pytest.raises(TypeError):
        phymul.step(model, "data")
    with pytest.raises(ValueError, match="dt must be a positive finite time"):
        data.dt = -1.0
    with pytest.raises(ValueError, match="dt must be a positive finite time"):
        data.dt = float("inf")
    with pytest.raises(TypeError, match="controller must be callable"):
        data.controller = 3
    with pytest.raises(ValueError):
        data.forces[0, 0] = 1.0
    with pytest.raises(ValueError):
        data.positions[:] = np.zeros((2, 3))  # NumPy refuses the shape


def test_an_unstable_step_raises_instability_error_naming_the_node():
    model, data = cube()
    data.dt = 50 * data.stable_dt
    with pytest.raises(phymul.InstabilityError) as caught:
        phymul.step(model, data, n=200)
    assert caught.value.node >= 0 and caught.value.time > 0.0
    assert "dt" in str(caught.value)


def test_a_controller_acts_before_each_step():
    model, data = cube()
    seen = []
    data.controller = lambda m, d: seen.append((d.steps, d.time))
    phymul.step(model, data, n=4)
    assert [s for s, _ in seen] == [0, 1, 2, 3]
    data.controller = None
    phymul.step(model, data, n=2)
    assert len(seen) == 4 and data.steps == 6

    def fails(m, d):
        raise RuntimeError("controller says no")

    data.controller = fails
    with pytest.raises(RuntimeError, match="controller says no"):
        phymul.step(model, data)
    assert data.steps == 6
