"""Trials (MNE-Epochs style): selection, drop log, average, bootstrap, epoching."""

import numpy as np
import pytest

from anklelab.data import Recording
from anklelab.errors import ParameterError
from anklelab.signals import Trials, bootstrap_weights, epoch, stack_recordings

CONDITIONS = np.array(["dorsi/100", "plantar/100", "dorsi/225", "none", "dorsi/100", "none"])


def _trials():
    data = np.arange(6 * 2 * 4, dtype=float).reshape(6, 2, 4)
    return Trials(data, 1000.0, ["angle", "torque"], {"condition": CONDITIONS}, tmin=-0.001)


def test_selection_by_condition_tags():
    t = _trials()
    assert t["dorsi/100"].selection.tolist() == [0, 4]
    assert t["dorsi"].selection.tolist() == [0, 2, 4]
    assert t["100"].selection.tolist() == [0, 1, 4]
    assert len(t["plantar/225"]) == 0
    assert t.conditions() == ["dorsi/100", "plantar/100", "dorsi/225", "none"]
    assert t[[1, 3]].metadata["condition"].tolist() == ["plantar/100", "none"]
    assert np.allclose(t.times, [-0.001, 0.0, 0.001, 0.002])
    assert t.get_data("torque").shape == (6, 4) and t.get_data(["torque"]).shape == (6, 1, 4)
    with pytest.raises(KeyError, match="force"):
        t.get_data("force")


def test_drop_log_keeps_every_original_trial():
    t = _trials().drop(CONDITIONS == "none", "unperturbed").drop([False, True, False, False], "bad")
    assert len(t) == 3
    assert t.drop_log == (
        (),
        ("bad",),
        (),
        ("unperturbed",),
        (),
        ("unperturbed",),
    )
    assert t.selection.tolist() == [0, 2, 4]
    assert t["dorsi"].drop_log == t.drop_log
    with pytest.raises(ParameterError, match="mask"):
        t.drop([True], "x")


def test_average_and_bootstrap():
    rng = np.random.default_rng(0)
    t = Trials(rng.normal(size=(50, 3, 20)), 1000.0, ["a", "b", "c"])
    assert np.allclose(t.average(), t.data.mean(axis=0))
    averages = t.bootstrap(200, 0.6, random_state=7)
    assert isinstance(averages, Trials) and averages.ch_names == t.ch_names
    boot = averages.data
    assert boot.shape == (200, 3, 20)
    assert np.array_equal(boot, t.bootstrap(200, 0.6, random_state=7).data)
    # each repetition is the mean of 30 distinct trials: check one against its subset
    w = bootstrap_weights(50, 200, 0.6, random_state=7)
    subset = np.flatnonzero(w[5])
    assert subset.size == 30 and np.allclose(boot[5], t.data[subset].mean(axis=0))
    # subsample means scatter around the full mean with variance s^2/m * (1 - m/n)
    sd = boot[:, 0, 0].std()
    expected = t.data[:, 0, 0].std(ddof=1) * np.sqrt((1 - 0.6) / 30)
    assert sd == pytest.approx(expected, rel=0.25)
    with pytest.raises(ParameterError, match="fraction"):
        bootstrap_weights(10, 5, 1.5)


def test_epoch_cuts_windows_and_logs_out_of_range_and_known_drops():
    rng = np.random.default_rng(1)
    data = rng.normal(size=(4, 2, 100))
    events = np.array([10, 50, 95, 60])
    t = epoch(
        data,
        1000.0,
        events,
        -0.005,
        0.010,
        ch_names=["x", "y"],
        metadata={"trial": np.arange(4)},
        lengths=[100, 100, 100, 62],
        drop_log=[(), ("no heel contact",), (), ()],
    )
    assert t.selection.tolist() == [0] and t.metadata["trial"].tolist() == [0]
    assert np.array_equal(t.data[0], data[0, :, 5:21])
    assert t.drop_log[1] == ("no heel contact",)
    assert t.drop_log[2] == t.drop_log[3] == ("window -0.005 .. 0.01 s leaves the recording",)
    assert t.tmin == pytest.approx(-0.005)


def test_stack_recordings_pads_with_the_last_value():
    recs = [
        Recording("a.csv", {"time_s": np.arange(3.0), "x": np.array([1.0, 2.0, 3.0])}),
        Recording("b.csv", {"time_s": np.arange(5.0), "x": np.arange(5.0)}),
    ]
    data, lengths = stack_recordings(recs, ["x"])
    assert lengths.tolist() == [3, 5]
    assert data[0, 0].tolist() == [1.0, 2.0, 3.0, 3.0, 3.0]


def test_stack_recordings_to_a_common_width():
    recs = [Recording("a.csv", {"time_s": np.arange(3.0), "x": np.array([1.0, 2.0, 3.0])})]
    data, _ = stack_recordings(recs, ["x"], width=5)
    assert data[0, 0].tolist() == [1.0, 2.0, 3.0, 3.0, 3.0]
    with pytest.raises(ValueError, match="width: expected at least the longest recording's 3"):
        stack_recordings(recs, ["x"], width=2)


def test_pick_keeps_the_named_channels_in_order():
    t = Trials(np.arange(12.0).reshape(2, 3, 2), 100.0, ["a", "b", "c"], {"k": [1, 2]}, tmin=-0.01)
    t = t.drop([True, False], "gone")
    picked = t.pick(["c", "a"])
    assert picked.ch_names == ("c", "a")
    assert np.array_equal(picked.get_data(), t.get_data(["c", "a"]))
    assert picked.drop_log == t.drop_log and picked.selection.tolist() == [1]
    assert picked.metadata["k"].tolist() == [2] and picked.tmin == t.tmin
