"""Job functions by name: how a ``"module:function"`` spec is checked, resolved and called.

A job function takes a :class:`~lamp.bench.jobs.Job` and returns a result.json ``dict``.
:func:`job_fn_spec` turns a callable into the name a job process imports it by (or raises
``ValueError`` in the parent); :func:`call_job` never raises: an exception in the job, or a
result that is not a ``dict``, comes back as ``("error", message, traceback)``. Shared by the
runner (:mod:`lamp.bench.runner`), the local pool (:mod:`lamp.bench.pool`) and its worker
processes (:mod:`lamp.bench.worker`), none of which need import another for it.
"""

from __future__ import annotations

import importlib
import traceback
from collections.abc import Callable
from typing import Any

from lamp.bench.jobs import Job

JobFn = Callable[[Job], dict[str, Any]]

#: Longest traceback kept in a results line.
MAX_TRACEBACK = 4000


def resolve_job_fn(spec: str | JobFn) -> JobFn:
    """A job function from ``"package.module:function"`` (or the callable itself)."""
    if callable(spec):
        return spec
    if not isinstance(spec, str) or ":" not in spec:
        raise ValueError(f"job_fn must be 'module:function' or a callable, got {spec!r}")
    module, _, name = spec.partition(":")
    try:
        fn = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as exc:
        raise ValueError(f"job_fn {spec!r} cannot be imported: {exc}") from exc
    if not callable(fn):
        raise ValueError(f"job_fn {spec!r} is not callable")
    return fn


def job_fn_spec(fn: str | JobFn) -> str:
    """``"module:function"`` for ``fn``; job processes import the job function by this name.

    Raises ``ValueError`` for a callable that cannot be imported by name (a lambda, a
    nested function, one defined in ``__main__``).
    """
    if isinstance(fn, str):
        resolve_job_fn(fn)  # fail early, in the parent, with a clear message
        return fn
    module, qual = getattr(fn, "__module__", None), getattr(fn, "__qualname__", "")
    if not module or module == "__main__" or "<" in qual or "." in qual:
        raise ValueError(f"job_fn {fn!r} must be a top-level function of an importable module")
    spec = f"{module}:{qual}"
    resolve_job_fn(spec)
    return spec


def call_job(spec: str | JobFn, job: Job) -> tuple[str, Any, str]:
    """Run the job; ``("ok", result, "")`` or ``("error", message, traceback)``."""
    try:
        result = resolve_job_fn(spec)(job)
        if not isinstance(result, dict):
            raise TypeError(f"job function returned {type(result).__name__}, expected dict")
        return ("ok", result, "")
    except Exception as exc:  # recorded as status "error", never lost
        return ("error", f"{type(exc).__name__}: {exc}", traceback.format_exc()[-MAX_TRACEBACK:])
