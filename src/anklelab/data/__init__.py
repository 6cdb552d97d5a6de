"""Sessions: the in-memory model, the CSV session directory, the native HDF5 store, MATLAB,
C3D files and mapped imports of lab layouts.

::

    from anklelab.data import load_session, save_session
    session = load_session("my_session_dir")     # or a .h5 / .mat file
    save_session(session, "my_session.h5")       # atomic; format="dir" writes CSV
"""

from anklelab.data.c3d import C3DFile, plate_load, read_c3d, read_c3d_files
from anklelab.data.c3d_import import import_c3d
from anklelab.data.capstan_ident import (
    IdentData,
    IdentRun,
    read_ident_directory,
    write_ident_directory,
)
from anklelab.data.directory import read_directory, write_directory
from anklelab.data.grf import grf_tables, write_grf_tables
from anklelab.data.hdf5 import H5_FORMAT, read_hdf5, write_hdf5
from anklelab.data.inspect import inspect_file
from anklelab.data.matlab import read_matlab
from anklelab.data.matlab_map import import_matlab
from anklelab.data.session import (
    BENCH_COLUMNS,
    BENCH_MANIFEST_COLUMNS,
    CALIBRATION_COLUMNS,
    DIRECTIONS,
    SESSION_FORMAT,
    WALKING_COLUMNS,
    WALKING_MANIFEST_COLUMNS,
    BenchTest,
    Recording,
    Session,
    SessionInfo,
    WalkingTrial,
)
from anklelab.data.store import (
    diff_sessions,
    load_session,
    save_session,
    session_hash,
    session_kind,
)
from anklelab.data.summary import summarize

__all__ = [
    "BENCH_COLUMNS",
    "BENCH_MANIFEST_COLUMNS",
    "CALIBRATION_COLUMNS",
    "DIRECTIONS",
    "H5_FORMAT",
    "SESSION_FORMAT",
    "WALKING_COLUMNS",
    "WALKING_MANIFEST_COLUMNS",
    "BenchTest",
    "C3DFile",
    "IdentData",
    "IdentRun",
    "Recording",
    "Session",
    "SessionInfo",
    "WalkingTrial",
    "diff_sessions",
    "grf_tables",
    "import_c3d",
    "import_matlab",
    "inspect_file",
    "load_session",
    "plate_load",
    "read_c3d",
    "read_c3d_files",
    "read_directory",
    "read_hdf5",
    "read_ident_directory",
    "read_matlab",
    "save_session",
    "session_hash",
    "session_kind",
    "summarize",
    "write_directory",
    "write_grf_tables",
    "write_hdf5",
    "write_ident_directory",
]
