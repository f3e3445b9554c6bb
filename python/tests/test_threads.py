"""Two Data of one Model stepped in two Python threads, the GIL released."""
import threading

import numpy as np
import pytest

import phymul
from conftest import EXAMPLES


def test_two_threads_step_two_data_of_one_model_as_in_turn():
    model = phymul.compile(phymul.load_scene(str(EXAMPLES / "hanging_cube.yaml")))
    alone = phymul.Data(model)
    phymul.step(model, alone, n=300)
    pair = [phymul.Data(model), phymul.Data(model)]
    pair[1].dt = pair[1].dt / 2  # the two differ, so a mix-up would show
    half = phymul.Data(model)
    half.dt = half.dt / 2
    phymul.step(model, half, n=300)
    threads = [threading.Thread(target=phymul.step, args=(model, d, 300)) for d in pair]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert np.array_equal(pair[0].positions, alone.positions)
    assert np.array_equal(pair[1].positions, half.positions)


def test_one_data_in_two_threads_at_once_is_refused():
    model = phymul.compile(phymul.load_scene(str(EXAMPLES / "hanging_cube.yaml")))
    data = phymul.Data(model)
    inside, release = threading.Event(), threading.Event()

    def hold(m, d):  # keeps the first thread inside phymul.step
        inside.set()
        release.wait(10)

    data.controller = hold
    first = threading.Thread(target=phymul.step, args=(model, data, 1))
    first.start()
    assert inside.wait(10)
    with pytest.raises(RuntimeError, match="another thread"):
        phymul.step(model, data)
    release.set()
    first.join()
    assert data.steps == 1
