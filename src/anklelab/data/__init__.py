"""Sessions: the in-memory model, the CSV session directory, the native HDF5 store, MATLAB,
C3D files and mapped imports of lab layouts.

::

    from anklelab.data import load_session, save_session
    session = load_session("my_session_dir")     # or a .h5 / .mat file
    save_session(session, "my_session.h5")       # atomic; format="dir" writes CSV
"""

from anklelab._lazy import lazy_exports

_EXPORTS = {
    "C3DFile": "c3d",
    "plate_load": "c3d",
    "read_c3d": "c3d",
    "read_c3d_files": "c3d",
    "import_c3d": "c3d_import",
    "IdentData": "capstan_ident",
    "IdentRun": "capstan_ident",
    "read_ident_directory": "capstan_ident",
    "write_ident_directory": "capstan_ident",
    "read_directory": "directory",
    "write_directory": "directory",
    "grf_tables": "grf",
    "write_grf_tables": "grf",
    "H5_FORMAT": "hdf5",
    "read_hdf5": "hdf5",
    "write_hdf5": "hdf5",
    "inspect_file": "inspect",
    "read_matlab": "matlab",
    "import_matlab": "matlab_map",
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
    "input_name": "store",
    "load_session": "store",
    "load_session_hashed": "store",
    "save_session": "store",
    "session_hash": "store",
    "session_kind": "store",
    "summarize": "summary",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
