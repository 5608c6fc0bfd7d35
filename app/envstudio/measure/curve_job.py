"""The error-against-N curve of one view measured in a child process, while the window draws
(the viewer's glossiness plot, ui/error_plot.py; issue 40 item 5).

:class:`CurveJob` copies the scene and the camera and starts a child process (spawned, as
the pem orbit bake's: no fork of a process whose GL and llvmpipe threads run). The copy goes
through a temporary file the child reads: a spawned child's arguments are written to it
through a pipe while it is still importing, and the window would wait on that for a scene
of megabytes. The child makes its own headless EGL context and session at the window's
cube size and takes :class:`~envstudio.measure.error_curve.CurveSteps`' steps, sending the
curve so far after each; the window takes what has arrived at each frame
(:meth:`CurveJob.poll`, never waiting). The child runs at a lower priority (:data:`NICE`),
so on a machine with few cores the window's frames come first.

A process, not a thread with a context of its own in the window's process:

- moderngl holds Python's GIL through every GL call, a read-back that waits for the
  software rasteriser to finish included (its extension never releases it): a thread
  reading back a one-second exact-reference pass would stop the window's thread for that
  second, as measuring between frames did.
- A step cannot be interrupted inside a GL call, and a microfacet step takes seconds; a
  process is terminated at once, so a change of view or closing the window ends it
  promptly, and its context, its threads and its memory go with it: nothing is left
  in the window's process.

The costs: the child's start (Python, the imports and the scene on the GPU again: a second
or two on a software renderer, small beside a point's seconds) and, as for every spawned
child, a program that opens the viewer from a script of its own must guard its start with
``if __name__ == "__main__":`` (the child imports that script again).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import pickle
import signal
import tempfile
import threading
import time
from collections.abc import Sequence
from multiprocessing.connection import Connection
from pathlib import Path

from tqdm import tqdm

from envstudio.engine.session import RenderSession
from envstudio.errors import UserError
from envstudio.measure.error_curve import CurveSteps, ErrorCurve

#: The child's niceness (added to the window's): the window's frames come first.
NICE = 10
#: Seconds to wait for the child to end once terminated (it ends at once; then it is killed).
JOIN_S = 2.0


def _measure(
    send: Connection,
    snapshot: str,
    cube_size: int,
    names: list[str],
    exponents: tuple[float, ...],
    size: tuple[int, int],
    ssaa: int,
) -> None:
    """The child: measure the pickled (scene, camera) in the file ``snapshot`` (removed once
    read) step by step, sending (points done, :class:`ErrorCurve`) after each step, or the
    first line of the :class:`UserError` that stopped it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the viewer handles Ctrl-C and stops us
    os.nice(NICE)  # before the context: llvmpipe's threads inherit it
    # tqdm's default lock is a named semaphore, which a terminated child would leave to
    # multiprocessing's resource tracker (a "leaked semaphore" warning at the window's
    # exit); only the child's own threads share it, which a thread lock serves
    tqdm.set_lock(threading.RLock())
    with open(snapshot, "rb") as file:
        scene, camera = pickle.load(file)
    os.unlink(snapshot)  # read: nothing left behind if the window is killed meanwhile
    try:
        session = RenderSession(scene, cube_size=cube_size)
        try:
            session.camera = camera
            steps = CurveSteps(session, names, exponents, size, ssaa)
            send.send((steps.done, steps.curve))
            while not steps.finished:
                steps.step()
                send.send((steps.done, steps.curve))
        finally:
            session.release()
    except UserError as exc:
        send.send(str(exc).splitlines()[0])
    finally:
        send.close()


class CurveJob:
    """Measure the error-against-N curve of a session's view in a child process.

    Parameters
    ----------
    session
        The window's session: its scene and camera are copied as they are now; the
        child renders at its cube size, with the display's defaults and every method's
        values set as :func:`~envstudio.measure.error_curve.error_curve` sets them.
    names, exponents, size, ssaa
        As :func:`~envstudio.measure.error_curve.error_curve`'s (size: width, height in
        pixels; exponents: Phong exponents N).
    """

    def __init__(
        self,
        session: RenderSession,
        names: Sequence[str],
        exponents: Sequence[float],
        size: tuple[int, int],
        ssaa: int,
    ):
        self.total = len(exponents)
        """Exponents in all."""
        self.done = 0
        """Exponents measured so far."""
        self.curve: ErrorCurve | None = None
        """The points so far (None until the child has made its session)."""
        self.error: str | None = None
        """Why the child stopped before the last point (one line), or None."""
        handle, name = tempfile.mkstemp(prefix="envstudio-curve-", suffix=".pickle")
        self._snapshot = Path(name)
        with os.fdopen(handle, "wb") as file:
            pickle.dump((session.scene, session.camera), file, pickle.HIGHEST_PROTOCOL)
        context = multiprocessing.get_context("spawn")
        self._receive, send = context.Pipe(duplex=False)
        self._process = context.Process(
            target=_measure,
            args=(
                send,
                name,
                session.gpu_scene.cube_size,
                list(names),
                tuple(float(n) for n in exponents),
                tuple(size),
                ssaa,
            ),
            daemon=True,
            name="envstudio-error-curve",
        )
        try:
            self._process.start()
        except BaseException:
            self.stop()
            raise
        finally:
            send.close()  # the child's copy only: the pipe ends when the child does
        self._last = time.monotonic()  # when the latest point came (or the child started)
        self._pace = 0.0  # seconds the latest point took

    @property
    def finished(self) -> bool:
        """Whether every point has arrived."""
        return self.done >= self.total

    @property
    def running(self) -> bool:
        """Whether the child is still measuring (neither finished, failed nor stopped)."""
        return self._process is not None and not self.finished and self.error is None

    def poll(self) -> None:
        """Take what the child has sent so far; never waits. Ends the job once the last
        point or an error has arrived."""
        if self._process is None:
            return
        try:
            while self._receive.poll():
                message = self._receive.recv()
                if isinstance(message, str):
                    self.error = message
                else:
                    done, self.curve = message
                    if done > self.done:
                        now = time.monotonic()
                        self._pace = (now - self._last) / (done - self.done)
                        self.done, self._last = done, now
        except EOFError:  # the child ended without its last point or an error: a crash
            if not self.finished and self.error is None:
                self._process.join(JOIN_S)
                self.error = f"the measurement stopped (exit status {self._process.exitcode})"
        if not self.running:
            self.stop()

    def seconds_left(self) -> float | None:
        """Seconds until the last point at the pace of the latest (a point's cost grows
        with N for the microfacet reference; the first includes the child's start),
        counted down since it came; None before the first point."""
        if self.done == 0 or not self.running:
            return None
        left = self._pace * (self.total - self.done) - (time.monotonic() - self._last)
        return max(left, 0.0)

    def stop(self) -> None:
        """End the child now (terminated if it is still measuring) and free the pipe and the
        scene's copy (if the child ended before reading it); the points so far stay in
        :attr:`curve`. Safe twice."""
        process, self._process = self._process, None
        if process is not None:
            if process.is_alive():
                process.terminate()
                process.join(JOIN_S)
                if process.is_alive():
                    process.kill()
                    process.join()
            process.close()
        self._receive.close()
        with contextlib.suppress(FileNotFoundError):
            self._snapshot.unlink()
