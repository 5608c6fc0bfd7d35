"""Per-pass timing: GPU timer queries on real GPUs, wall clock around ``finish()`` on software.

On llvmpipe timer queries under-report (1–6 ms where the wall clock with
``ctx.finish()`` says 16–33 ms, ../shared/GPU.md), so software renderers are
timed with ``time.perf_counter`` after ``ctx.finish()`` at both ends of a pass.
:attr:`PassTimer.clock` says which clock was used.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator

import moderngl

from envstudio.gpu.context import is_software_renderer


class PassTimer:
    """Measures named passes of a frame in milliseconds.

    Parameters
    ----------
    ctx
        The context whose work is timed.
    enabled
        When False, :meth:`measure` costs nothing and records nothing.
    """

    def __init__(self, ctx: moderngl.Context, enabled: bool = True):
        self.ctx = ctx
        self.enabled = enabled
        self.clock = "wall+finish" if is_software_renderer(ctx) else "gpu-timer-query"
        self.times_ms: dict[str, float] = {}
        self._queries: dict[str, moderngl.Query] = {}

    def begin_frame(self) -> None:
        """Forget the previous frame's times."""
        self.times_ms = {}

    @contextlib.contextmanager
    def measure(self, name: str) -> Iterator[None]:
        """Time the GL work issued inside the ``with`` block as pass ``name``."""
        if not self.enabled:
            yield
            return
        if self.clock == "wall+finish":
            self.ctx.finish()
            start = time.perf_counter()
            yield
            self.ctx.finish()
            elapsed = (time.perf_counter() - start) * 1e3
        else:
            query = self._queries.get(name)
            if query is None:
                query = self._queries[name] = self.ctx.query(time=True)
            with query:
                yield
            elapsed = query.elapsed / 1e6
        self.times_ms[name] = self.times_ms.get(name, 0.0) + elapsed

    def release(self) -> None:
        """Forget the queries; safe to call twice.

        moderngl 5 gives ``Query`` no ``release``: its GL objects go with the context.
        """
        self._queries.clear()
