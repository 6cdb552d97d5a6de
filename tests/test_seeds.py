"""Every stochastic public function takes ``seed: int | numpy.random.Generator`` (DESIGN.md 2).

The sweep reads the signatures of every name in every module's ``__all__``; the behavioural
tests check that a Generator gives the result of the int it was seeded with, and that a
Generator passed to several calls continues its stream.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import pkgutil

import numpy as np
import pytest

import anklelab
from anklelab._params import Parameters
from anklelab.control import RampHold, calibration_schedule
from anklelab.platforms import load_platform
from anklelab.sim import Artefacts, sample_gait
from anklelab.sim.sensors import force_channels, goniometer_reading, load_cell_reading

RANDOM_PARAMETERS = {"seed", "rng", "random_state", "generator"}


def _record(cls: type) -> bool:
    """A frozen dataclass: its ``__init__`` only stores its fields (its methods are checked)."""
    return dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen


def _public_callables():
    for info in pkgutil.walk_packages(anklelab.__path__, "anklelab."):
        if info.name.startswith("anklelab.commands"):
            continue  # CLI options are ints typed on the command line
        module = importlib.import_module(info.name)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if inspect.isfunction(obj):
                yield f"{info.name}.{name}", obj
            elif inspect.isclass(obj) and not issubclass(obj, Parameters):
                # settings models, and the fields of frozen records (a study's cell), hold a
                # serialisable int seed (written to results.json, hashed into a cell's key)
                init = not _record(obj)
                for attr, member in vars(obj).items():
                    func = getattr(member, "__func__", member)
                    if inspect.isfunction(func) and (
                        (attr == "__init__" and init) or attr[0] != "_"
                    ):
                        yield f"{info.name}.{name}.{attr}", func


def test_every_random_parameter_is_a_seed_that_accepts_an_int_or_a_generator():
    found, wrong = [], []
    for qualname, func in _public_callables():
        for param in inspect.signature(func).parameters.values():
            if param.name in RANDOM_PARAMETERS:
                found.append(qualname)
                annotation = str(param.annotation)
                accepts = annotation == "Seed" or {"int", "np.random.Generator"} <= set(
                    annotation.replace(" ", "").split("|")
                )
                if param.name == "rng" or not accepts:
                    wrong.append(f"{qualname}({param.name}: {annotation})")
    assert len(found) > 10  # the sweep sees the API
    assert wrong == []


PARAMS = load_platform("perturberator")
MOVE = RampHold(0.035, 0.075, 0.1, 0.075)
CALLS = {
    "calibration_schedule": lambda seed: calibration_schedule(MOVE, 10, 10.0, 2.0, 0.5, seed),
    "sample_gait": lambda seed: sample_gait(PARAMS.gait, 4, seed),
    "force_channels": lambda seed: force_channels(np.zeros((2, 6, 50)), PARAMS, Artefacts(), seed),
    "goniometer_reading": lambda seed: goniometer_reading(
        np.linspace(0, 0.2, 50), PARAMS, Artefacts(), seed
    ),
    "load_cell_reading": lambda seed: load_cell_reading(np.ones(50), PARAMS, Artefacts(), seed),
}


def _flat(result):
    fields = vars(result).values() if hasattr(result, "__dataclass_fields__") else result
    if isinstance(result, np.ndarray):
        fields = [result]
    return np.concatenate([np.ravel(np.asarray(field, dtype=float)) for field in fields])


@pytest.mark.parametrize("name", list(CALLS))
def test_a_generator_gives_the_result_of_its_seed_and_continues_its_stream(name):
    call = CALLS[name]
    by_int = _flat(call(7))
    assert np.array_equal(by_int, _flat(call(7)))
    assert np.array_equal(by_int, _flat(call(np.random.default_rng(7))))
    assert not np.array_equal(by_int, _flat(call(8)))
    shared = np.random.default_rng(7)
    assert np.array_equal(by_int, _flat(call(shared)))
    assert not np.array_equal(by_int, _flat(call(shared)))
