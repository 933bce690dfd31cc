"""Borrowed views for Gspi's compiled hot loops: the same data without a reference count.

Numba counts references to arrays and typed lists with atomic operations: every array
(or tuple of them, as a :class:`~lamp.mrmp.gspi_kernels.Graph` of 5 arrays or a
:class:`~lamp.mrmp.goal_distances.GoalDistances` of 19 arrays and lists) handed to an
inlined helper is counted up when bound and down when the helper ends, unless LLVM can
pair the two, which it cannot across a helper's loops and calls. In the steps of a fleet
(one such helper per robot, per candidate move, per goal-swap pair) those atomic
operations took about half the time of the steps, and a third of the repair's.

:func:`borrowed` gives the value with its meminfo (and an array's parent) left out:
binding it costs no atomic operation (Numba skips a null meminfo). A kernel borrows its
*arguments* on entry; its caller holds them for the whole call, so the views stay valid.
Never borrow an array the kernel itself allocates or replaces (its owner may be freed
after its last use), and never keep a borrowed view beyond the call. An item read from a
borrowed typed list is an ordinary, counted reference (the list may replace it).
"""

from __future__ import annotations

from typing import Any

from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

__all__ = ["borrowed"]


def _borrow(context: Any, builder: Any, ty: Any, val: Any) -> Any:
    """The LLVM value ``val`` of type ``ty`` with every meminfo (and parent) nulled,
    member by member in tuples; other values as they are."""
    if isinstance(ty, types.Array):
        out = context.make_array(ty)(context, builder, value=val)
        out.meminfo = cgutils.get_null_value(out.meminfo.type)
        out.parent = cgutils.get_null_value(out.parent.type)
        return out._getvalue()
    if isinstance(ty, types.ListType):
        lst = cgutils.create_struct_proxy(ty)(context, builder, value=val)
        lst.meminfo = cgutils.get_null_value(lst.meminfo.type)
        return lst._getvalue()
    if isinstance(ty, types.BaseTuple):
        for k, member in enumerate(ty.types):
            part = _borrow(context, builder, member, builder.extract_value(val, k))
            val = builder.insert_value(val, part, k)
    return val


@intrinsic
def borrowed(typingctx: Any, x: Any) -> Any:
    """``x`` (an array, a typed list, or a tuple or named tuple of them and other values)
    without reference counts: the same data and type (module docstring)."""
    if not isinstance(x, (types.Array, types.ListType, types.BaseTuple)):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        return _borrow(context, builder, x, args[0])

    return x(x), codegen
