"""The render session a worker keeps from one scene of the atlas to the next.

Scenes of one environment differ in their reflector, camera and glossiness only, and what
the methods derive from the environment alone (parallax's Phong chain, Banks' 3D map,
Kautz's mip chain, the scene's cube map and SH9) is keyed by the environment's revision
(shading.gpu_scene), as when the viewer swaps the reflector: kept, those are built once per
environment and worker instead of once per scene, and so is the pyramid the exact
references' glossy lobes descend (:attr:`KeptSession.lobes`). Every method's and the
display's values go back to a fresh session's (RenderSession.reset_values) before each
scene, so a cell measures what a fresh session would.
"""

from __future__ import annotations

import numpy as np

from envstudio.engine.session import RenderSession
from envstudio.measure.exact_lobes import LobeEvaluator
from envstudio.scene.graph import Scene

__all__ = ["KEPT", "KeptSession", "release_kept"]


class KeptSession:
    """One render session at a time, kept while the scenes' environment stays the same."""

    def __init__(self) -> None:
        self._session: RenderSession | None = None
        self._lobes: LobeEvaluator | None = None
        self.made = 0  # sessions made: one per environment run, for the tests

    @property
    def lobes(self) -> LobeEvaluator:
        """The kept session's evaluation of the exact references' glossy lobes (made on first
        use), whose pyramid serves every scene of the environment."""
        if self._session is None:
            raise RuntimeError("no kept session")
        if self._lobes is None:
            self._lobes = LobeEvaluator(self._session.ctx, self._session.programs)
        return self._lobes

    def session_for(self, scene: Scene) -> RenderSession:
        """A session showing ``scene``: the kept one with ``scene``'s reflectors and camera
        where its environment holds the same radiance, else a new one (the old released).
        """
        session = self._session
        if session is not None and _same_environment(session.scene, scene):
            session.gpu_scene.set_nodes(scene.nodes)
            session.scene.camera = session.camera = scene.camera
            session.scene.variant = scene.variant
            session.reset_values()
            return session
        self.release()
        self._session = RenderSession(scene)
        self.made += 1
        return self._session

    def release(self) -> None:
        """Free the kept session (its GPU resources and context); safe twice."""
        if self._lobes is not None:
            self._lobes.release()
            self._lobes = None
        if self._session is not None:
            self._session.release()
            self._session = None


def _same_environment(shown: Scene, wanted: Scene) -> bool:
    """Whether a kept session may show ``wanted``: equal radiance pixels, and neither scene
    with local objects (a capture of them would depend on the reflector; the atlas's
    scenes have none)."""
    a, b = shown.environment.radiance, wanted.environment.radiance
    return (
        a.shape == b.shape
        and (a is b or np.array_equal(a, b))
        and not shown.local_objects()
        and not wanted.local_objects()
    )


#: This process's kept session (a worker's, or the atlas's own with one job).
KEPT = KeptSession()


def release_kept() -> None:
    """Free this process's kept session (run on a Dask worker when the atlas is done)."""
    KEPT.release()
