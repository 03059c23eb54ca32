"""A run whose samples cannot fit in the machine's memory is refused before any work, through
every route (herringbone.arguments.check_run_times): one ValueError naming both arguments, the
size and what is allowed, not numpy's allocation error at the end of the model's build."""
import os

import pytest

import herringbone
from herringbone import arguments

GIB = 2 ** 30


@pytest.fixture
def machine_of_one_gib(monkeypatch):
    """The check's view of the machine: 1 GiB of physical memory, whatever this one has."""
    monkeypatch.setattr(arguments, "physical_memory", lambda: GIB, raising=False)


@pytest.fixture
def no_model(monkeypatch):
    """Building a model fails the test: the check must come before it."""
    from herringbone.integrate import compiled_stepper, reference

    def refuse(*args, **kwargs):
        raise AssertionError("the work began before the samples were checked")

    monkeypatch.setattr(compiled_stepper, "GearTrainModel", refuse)
    monkeypatch.setattr(reference, "GearTrainModel", refuse, raising=False)


@pytest.mark.parametrize("route", ["simulate", "reference_simulate"])
def test_a_run_too_large_for_the_memory_is_one_value_error(route, reference_scene,
                                                           machine_of_one_gib, no_model):
    """1e5 s every 1e-7 s: 1e12 samples of 19 values, 138 TiB (numpy said "Unable to allocate
    7.28 TiB" for the times alone)."""
    with pytest.raises(ValueError) as raised:
        getattr(herringbone, route)(reference_scene, stop_time=1e5, output_interval=1e-7)
    message = str(raised.value)
    assert message.startswith("stop_time 100000 s with output_interval 1e-07 s is 1e+12 "
                              "samples of 19 values (the outputs and the time), 138 TiB; "
                              "allowed: at most 3.53e+06 samples of this scene, within 50% of "
                              "this machine's 1 GiB of memory"), message
    assert "\n" not in message


def test_the_samples_of_the_scene_itself_are_checked(reference_scene, machine_of_one_gib,
                                                     no_model):
    """The scene's own [experiment] span (no arguments given) is held to the same bound."""
    dense = herringbone.scene_from_dict({"experiment": {"stop_time": 100.0,
                                                        "output_interval": 1e-6}})
    with pytest.raises(ValueError, match=r"^stop_time 100 s with output_interval 1e-06 s is "
                                         r"1e\+08 samples"):
        herringbone.simulate(dense)


def test_what_fits_runs_and_an_unknown_memory_is_not_checked(reference_scene, monkeypatch):
    scene = reference_scene
    assert arguments.samples_problem(scene, 0.1, 1e-4) is None
    monkeypatch.setattr(arguments, "physical_memory", lambda: None, raising=False)
    assert arguments.samples_problem(scene, 1e5, 1e-7) is None
    if hasattr(os, "sysconf"):
        monkeypatch.undo()
        assert arguments.physical_memory() > 0
