"""Native objects a run keeps, released when the process ends (bench decision B83).

The bench's objects reference each other in cycles (the MLC, its channel link, the operator panel, the manual
motion), so what they hold is freed only by a garbage collection. `hil`'s exit skips the finalization's
collections (`hil.cli`, B83); ruckig's nanobind objects left in such a cycle would then never be freed, and
nanobind prints a leak report on stderr when the interpreter ends. `release_at_exit` drops the owner's references
to them in the atexit handlers (weakref.finalize's), before the finalization: freed by their reference count.
"""

from __future__ import annotations

import weakref


def release_at_exit(owner: object, *names: str) -> None:
    """At exit, set these attributes of `owner` to None if it is still alive; nothing if it was freed before."""
    weakref.finalize(owner, _release, weakref.ref(owner), names)


def _release(ref: weakref.ref, names: tuple[str, ...]) -> None:
    owner = ref()
    if owner is not None:  # the process ends with the owner alive (in the bench's cycles)
        for name in names:
            setattr(owner, name, None)
