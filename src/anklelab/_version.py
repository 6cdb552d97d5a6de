"""The installed anklelab version (recorded in every output file)."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("anklelab")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"
