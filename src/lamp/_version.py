"""The package version: read from the installed distribution's metadata.

``pyproject.toml`` is the one place the version is written; this module only reads what
pip recorded from it. A source tree imported without being installed reports
:data:`UNKNOWN_VERSION`.
"""

from __future__ import annotations

from importlib import metadata

#: ``__version__`` of a source tree that is not installed.
UNKNOWN_VERSION = "0+unknown"

try:
    __version__ = metadata.version("lamp")
except metadata.PackageNotFoundError:  # pragma: no cover - only without an installation
    __version__ = UNKNOWN_VERSION
