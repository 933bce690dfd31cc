"""The exceptions ``lamp`` raises on purpose.

Every error a caller can act on derives from :class:`LampError`; bad input to a public
function or file is an :class:`InputError` (also a ``ValueError``, so that code written
against the standard exception keeps working). Anything else escaping from ``lamp`` is a
bug: the planners never turn an unexpected exception into "infeasible".
"""

from __future__ import annotations

__all__ = ["InputError", "LampError"]


class LampError(Exception):
    """Base class of the errors ``lamp`` raises deliberately."""


class InputError(LampError, ValueError):
    """An argument, file or field is invalid; the message names it and the value."""
