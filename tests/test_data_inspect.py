"""``anklelab inspect FILE``: the tree of a MATLAB (v5 and v7.3), HDF5 or C3D file."""

from __future__ import annotations

import ezc3d
import h5py
import numpy as np
import pytest
import scipy.io
from typer.testing import CliRunner

from anklelab.cli import app
from anklelab.data.c3d import read_c3d
from anklelab.data.inspect import inspect_file
from anklelab.errors import SessionFormatError
from tests.c3d_files import write_plate_file
from tests.test_data_matlab import write_mat73

LAYOUT = {
    "fs": 1000.0,
    "trials": [
        {"GRF": np.ones((50, 3)), "name": "a"},
        {"GRF": np.ones((60, 3)), "name": "b"},
    ],
    "dorsiflexion": {"t225": {"Fz": np.zeros((40, 7))}},
}


@pytest.mark.parametrize("version", ["v5", "v7.3"])
def test_matlab_tree_is_what_a_mapping_sees(tmp_path, version):
    path = tmp_path / "s.mat"
    if version == "v5":
        trials = np.empty((1, 2), dtype=[("GRF", object), ("name", object)])
        trials[0, 0], trials[0, 1] = (np.ones((50, 3)), "a"), (np.ones((60, 3)), "b")
        scipy.io.savemat(path, {"S07": LAYOUT | {"trials": trials}})
    else:
        write_mat73(path, {"S07": LAYOUT})
    lines = inspect_file(path)
    text = "\n".join(lines)
    assert "S07  struct" in text
    assert "fs  float64 scalar 1000" in text
    assert "trials  1x2 struct array" in text
    assert "GRF  float64 50x3" in text
    assert "name  char 'a'" in text
    assert "      t225  struct" in text and "Fz  float64 40x7" in text


def test_hdf5_tree_shows_links_without_following_them(tmp_path):
    path = tmp_path / "f.h5"
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "anything"
        f.create_group("g").create_dataset("x", data=np.arange(6.0).reshape(2, 3))
        f["g/x"].attrs["units"] = "N"
        f["soft"] = h5py.SoftLink("/g/x")
        f["outside"] = h5py.ExternalLink("/etc/passwd", "/data")
    text = "\n".join(inspect_file(path))
    assert "@format = 'anything'" in text
    assert "g/" in text and "x  float64 2x3" in text and "@units = 'N'" in text
    assert "soft  -> link to /g/x (not followed)" in text
    assert "outside  -> link to /etc/passwd/data (not followed)" in text


def test_c3d_tree_lists_channels_plates_and_parameters(tmp_path):
    path, _ = write_plate_file(tmp_path / "p.c3d", 3, "z", "mm")
    result = CliRunner().invoke(app, ["inspect", str(path)])
    assert result.exit_code == 0, result.output
    assert "analog 1000 Hz, 1200 samples" in result.output
    assert "'Ffz4' [N]" in result.output
    assert "1: type 3, channels Ffx12, Ffx34" in result.output
    assert "FORCE_PLATFORM" in result.output and "TYPE = 3" in result.output


def _point_units(c):
    c["parameters"]["POINT"]["UNITS"]["value"] = ["in"]


def _origin_nan(c):
    c["parameters"]["FORCE_PLATFORM"]["ORIGIN"]["value"] = np.array([[np.nan], [0.0], [40.0]])


@pytest.mark.parametrize(
    ("change", "note"),
    [
        (_point_units, "note: POINT:UNITS = 'in'; expected one of m, cm, mm"),
        (_origin_nan, "note: plate 1 (type 2): FORCE_PLATFORM:ORIGIN [nan, 0, 40] is not finite"),
    ],
)
def test_a_c3d_file_that_cannot_be_imported_is_still_shown(tmp_path, change, note):
    """What keeps a file from being read as a session (a unit, a plate's geometry) is a note:
    the tree and every parameter are printed, so that the user sees what to fix."""
    path, _ = write_plate_file(tmp_path / "p.c3d", 2, "z", "mm")
    c = ezc3d.c3d(str(path))
    change(c)
    c.write(str(path))
    with pytest.raises(SessionFormatError):
        read_c3d(path)
    result = CliRunner().invoke(app, ["inspect", str(path)])
    assert result.exit_code == 0, result.output
    assert note in result.output
    assert "'Fz' [N]" in result.output and "force platforms (0):" in result.output
    assert "ORIGIN = 3x1 float64:" in result.output and "UNITS = ['" in result.output


def test_inspect_errors(tmp_path):
    expected = r"expected a \.mat, \.c3d or HDF5 file$"
    with pytest.raises(SessionFormatError, match=rf"nope\.mat: does not exist; {expected}"):
        inspect_file(tmp_path / "nope.mat")
    with pytest.raises(
        SessionFormatError, match=rf"\S+: is a directory, not a regular file; {expected}"
    ):
        inspect_file(tmp_path)
    (tmp_path / "x.h5").write_bytes(b"not hdf5")
    with pytest.raises(SessionFormatError, match=r"x\.h5: cannot open as HDF5"):
        inspect_file(tmp_path / "x.h5")
