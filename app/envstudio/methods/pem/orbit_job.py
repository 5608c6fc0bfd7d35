"""The full-orbit PEM baked in the background while the viewer runs (issue 31).

:class:`OrbitBakeJob` bakes an :class:`~envstudio.methods.pem.bake.orbit.OrbitStore`'s
missing views in one child process (spawned: no fork after Embree's and GL's
threads), nearest the camera first. The viewer's frame never waits on it: it
polls the parts folder at most every :data:`POLL_S` seconds. When the camera
turns to views the child will not reach soon, the child is stopped and started
again in the new order (at most every :data:`RESTART_S` seconds); the view it
was baking is lost, every finished one is kept (parts are written atomically),
and so quitting the viewer mid-bake resumes next time.
"""

from __future__ import annotations

import multiprocessing
import signal
import time

from envstudio.methods.pem.bake.orbit import OrbitStore, nearest_first
from envstudio.scene.camera import OrbitCamera

__all__ = ["FAILED_RETRY_S", "JOIN_S", "POLL_S", "RESTART_S", "OrbitBakeJob"]

#: Seconds between looks at the parts folder.
POLL_S = 0.5
#: Least seconds between restarts of the child in a new order.
RESTART_S = 2.0
#: Seconds before a child that failed is started again.
FAILED_RETRY_S = 30.0
#: Seconds a stopped child has to end before it is killed.
JOIN_S = 5.0


def _bake_in_order(
    scene: str, step: tuple[float, float], parameters: dict, gl: bool, order: list[int]
) -> None:
    """The child: bake ``order``'s views of the scene's orbit in this process."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the viewer handles Ctrl-C and stops us
    from envstudio.methods.pem.lookups_gl import GlLookups

    store = OrbitStore(scene, GlLookups if gl else None, step, parameters=parameters)
    store.bake(order, workers=0)


class OrbitBakeJob:
    """Bake a store's missing views in a child process, nearest the camera first.

    Parameters
    ----------
    store
        The orbit to complete.
    scene
        The scene file (or shipped name) the child loads.
    """

    def __init__(self, store: OrbitStore, scene: str):
        self.store = store
        self.scene = scene
        self._process: multiprocessing.Process | None = None
        self._order: list[int] = []
        self._done = store.done()
        self._polled = time.perf_counter()
        self._started = 0.0
        self._done_at_start = len(self._done)
        #: Why the last child stopped before the orbit was complete ("" when it did not).
        self.failure = ""
        self._ended: float | None = None  # when the child was first seen to have ended

    def done(self) -> set[int]:
        """The views baked so far (refreshed at most every :data:`POLL_S`)."""
        now = time.perf_counter()
        if now - self._polled >= POLL_S:
            self._done = self.store.done()
            self._polled = now
        return self._done

    @property
    def running(self) -> bool:
        """Whether the child is baking."""
        return self._process is not None and self._process.is_alive()

    def request(self, camera: OrbitCamera, needed: list[int]) -> None:
        """Make sure the views ``needed`` now are baked soon, and the rest after them.

        Starts the child if the orbit is not complete and none runs; restarts it in
        the order nearest ``camera`` when a needed view is not among the next
        views it will bake.
        """
        done = self.done()
        missing = [v for v in range(self.store.total) if v not in done]
        if not missing:
            return
        if self._process is not None and not self.running:  # it ended: finished or failed
            code, now = self._process.exitcode, time.perf_counter()
            if self._ended is None:
                self._ended = now
                self.failure = "" if code == 0 else f"the background bake stopped (exit {code})"
            if now - self._ended < (RESTART_S if code == 0 else FAILED_RETRY_S):
                return
            self._process, self._ended = None, None
        if self.running:
            upcoming = [v for v in self._order if v not in done][:2]
            late = [v for v in needed if v not in done and v not in upcoming]
            if not late or time.perf_counter() - self._started < RESTART_S:
                return
            self.stop()
        self._order = nearest_first(self.store.space, camera, missing)
        context = multiprocessing.get_context("spawn")
        self._process = context.Process(
            target=_bake_in_order,
            args=(
                self.scene,
                self.store.step,
                self.store.parameters,
                self.store.gl_lookups is not None,
                self._order,
            ),
            daemon=True,
            name="envstudio-pem-orbit",
        )
        self._process.start()
        self._started = time.perf_counter()
        self._done_at_start = len(done)

    def seconds_left(self) -> float | None:
        """Time left at the rate of this run so far (None before its first view)."""
        done = len(self.done())
        rate = (done - self._done_at_start) / max(time.perf_counter() - self._started, 1e-9)
        if not self.running or rate <= 0.0:
            return None
        return (self.store.total - done) / rate

    def stop(self) -> None:
        """Stop the child and wait for its end (its finished views are kept, the view it
        was writing is removed); safe to call twice."""
        process, self._process, self._ended = self._process, None, None
        if process is None:
            return
        process.terminate()
        process.join(JOIN_S)
        if process.is_alive():  # SIGTERM waits while the child is in the kernel (an fsync)
            process.kill()
            process.join()
        process.close()
        self.store.discard_unfinished()
