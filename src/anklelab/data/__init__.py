"""Sessions: the in-memory model, the CSV session directory, the native HDF5 store, MATLAB.

::

    from anklelab.data import load_session, save_session
    session = load_session("my_session_dir")     # or a .h5 / .mat file
    save_session(session, "my_session.h5")       # atomic; format="dir" writes CSV
"""

from anklelab._lazy import lazy_exports

_EXPORTS = {
    "IdentData": "capstan_ident",
    "IdentRun": "capstan_ident",
    "read_ident_directory": "capstan_ident",
    "write_ident_directory": "capstan_ident",
    "read_directory": "directory",
    "write_directory": "directory",
    "H5_FORMAT": "hdf5",
    "read_hdf5": "hdf5",
    "write_hdf5": "hdf5",
    "read_matlab": "matlab",
    "BENCH_COLUMNS": "session",
    "BENCH_MANIFEST_COLUMNS": "session",
    "CALIBRATION_COLUMNS": "session",
    "DIRECTIONS": "session",
    "SESSION_FORMAT": "session",
    "WALKING_COLUMNS": "session",
    "WALKING_MANIFEST_COLUMNS": "session",
    "BenchTest": "session",
    "Recording": "session",
    "Session": "session",
    "SessionInfo": "session",
    "WalkingTrial": "session",
    "diff_sessions": "store",
    "load_session": "store",
    "save_session": "store",
    "session_hash": "store",
    "session_kind": "store",
    "summarize": "summary",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
