"""The installed anklelab version (recorded in every output file), and a fingerprint of its code."""

import functools
import hashlib
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

try:
    __version__ = version("anklelab")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"


_SHIPPED = frozenset({".py", ".toml", ".typed"})
"""The package's own files: its code, its shipped parameter sets and its typing marker."""


@functools.cache
def code_fingerprint() -> str:
    """A hash of the package's own files (its code and shipped parameter sets), 16 hex digits.

    Finer than :data:`__version__`, which a source tree keeps across edits: stored results that
    are reused instead of computed again (a study's sessions, a batch's) are keyed by it, so
    that results of other code are never taken for this code's. Caches (``__pycache__``) and
    hidden files (an editor's swap file) are left out.
    """
    root = Path(__file__).parent
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*")):
        relative = path.relative_to(root)
        hidden = any(part.startswith(".") or part == "__pycache__" for part in relative.parts)
        if path.suffix in _SHIPPED and path.is_file() and not hidden:
            digest.update(relative.as_posix().encode() + b"\0")
            digest.update(path.read_bytes())
    return digest.hexdigest()[:16]
