"""Metadata trees (truth, provenance, session.toml extras) survive JSON, HDF5 and TOML exactly."""

import tomllib

import h5py
import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from anklelab.data import _toml
from anklelab.data._tree import (
    canonical,
    from_json,
    link_name,
    read_h5_tree,
    to_json,
    tree_differences,
    unlink_name,
    write_h5_tree,
)

# Storable text: no NUL (HDF5) and no lone surrogates (no UTF-8 encoding); both are rejected.
storable = st.characters(exclude_characters="\x00", exclude_categories=("Cs",))
keys = st.text(storable, min_size=1, max_size=8)
text = st.text(storable)
floats = st.floats(allow_nan=True, allow_infinity=True)
scalars = st.one_of(st.none(), st.booleans(), st.integers(-(2**62), 2**62), floats, text)
numeric_arrays = st.one_of(
    arrays(np.float64, st.integers(0, 5), elements=floats),
    arrays(np.int64, st.tuples(st.integers(1, 3), st.integers(1, 3))),
    arrays(np.bool_, st.integers(1, 4)),
)
leaves = st.one_of(scalars, numeric_arrays, st.lists(text, min_size=1, max_size=3).map(tuple))
trees = st.recursive(
    st.dictionaries(keys, leaves, max_size=4),
    lambda children: st.dictionaries(keys, st.one_of(leaves, children), max_size=4),
    max_leaves=12,
)


@settings(max_examples=60, deadline=None)
@given(trees)
def test_json_round_trip(tree):
    assert tree_differences(from_json(to_json(tree)), canonical(tree)) == []


@settings(max_examples=40, deadline=None)
@given(trees)
def test_hdf5_round_trip(tmp_path_factory, tree):
    path = tmp_path_factory.mktemp("h5") / "t.h5"
    with h5py.File(path, "w", track_order=True) as f:
        write_h5_tree(f.create_group("t", track_order=True), tree)
    with h5py.File(path, "r") as f:
        assert tree_differences(read_h5_tree(f["t"]), canonical(tree)) == []


toml_leaves = st.one_of(
    st.booleans(),
    st.integers(-(2**62), 2**62),
    floats,
    text,
    arrays(np.float64, st.integers(1, 4), elements=st.floats(allow_nan=False)),
)
toml_trees = st.recursive(
    st.dictionaries(keys, toml_leaves, max_size=4),
    lambda children: st.dictionaries(keys, st.one_of(toml_leaves, children), max_size=3),
    max_leaves=10,
)


@settings(max_examples=60, deadline=None)
@given(toml_trees)
@example({"0\n": False})  # a key that ends in a newline must be quoted
def test_toml_round_trip(tree):
    assert tree_differences(canonical(tomllib.loads(_toml.dumps(tree))), canonical(tree)) == []


@pytest.mark.parametrize("name", ["plain", "a/b", "100%", "%2F", ".", "..", "a%2Fb/c"])
def test_link_names_are_reversible(name):
    link = link_name(name)
    assert "/" not in link and link != "."
    assert unlink_name(link) == name


def test_differences_are_reported_by_key():
    a = {"x": {"y": np.array([1.0, np.nan])}, "z": 1}
    b = {"x": {"y": np.array([1.0, 2.0])}, "w": 1}
    assert tree_differences(canonical(a), canonical(b)) == [
        "w: only in second",
        "x.y: arrays differ",
        "z: only in first",
    ]


@pytest.mark.parametrize(
    "tree",
    [
        {"": 1},
        {"a\x00": 1},
        {"a": "b\x00"},
        {"a": ("x", "\x00")},
        {1: 2},
        {"\ud800": None},
        {"a": "\udfff"},
        {"a": ("x", "\ud800")},
    ],
)
def test_unstorable_keys_and_text_are_rejected(tree):
    with pytest.raises(ValueError, match=r"UTF-8 (strings )?without NUL"):
        canonical(tree)
