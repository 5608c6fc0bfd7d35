"""One set of 12 baked radiance sphere maps of ``rsibr``: bake, cache, textures, warp.

``rsibr`` keeps one set for its BRDF's maps and, for Phong with k_d > 0, a
second of Lambertian maps warped by the normal (seed 002 §3: "primarily diffuse
BRDFs suggest a warp that matches surface normal directions"). A set is keyed by
(scene, static environment revision, BRDF, its bake values, map size, samples); a new key
starts a bake, which loads from the user cache when it can and otherwise runs on
the GPU, at once headless or a few views per frame within the window's budget
while the old maps stay in use.
"""

from __future__ import annotations

import sys
import time

import moderngl
import numpy as np

from envstudio.envmap.conversions import read_cube
from envstudio.io.cache_entries import discard
from envstudio.methods.rsibr.bake import bake as rb
from envstudio.methods.rsibr.generator import MapGenerator
from envstudio.methods.rsibr.gpu_bake import GpuBaker
from envstudio.methods.rsibr.warp import view_frame
from envstudio.plugin import InputFileError, StaticEnvironment

__all__ = ["MapSet"]


class MapSet:
    """The baked maps of one BRDF, their textures and their map generator.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    """

    def __init__(self, ctx: moderngl.Context, programs):
        self.ctx = ctx
        self.programs = programs
        #: The installed bake, or None before the first.
        self.bake: rb.RsibrBake | None = None
        #: One texture per view of :attr:`bake`.
        self.textures: list[moderngl.Texture] = []
        #: Seconds the last bake took on the GPU; None when it came from the cache.
        self.last_bake_seconds: float | None = None
        self._key: tuple | None = None
        self._pending: dict | None = None
        self._env_keys: dict[tuple, str] = {}
        self._generator: MapGenerator | None = None

    @property
    def pending(self) -> dict | None:
        """The bake under way: its ``key``, ``views`` and the ``maps`` done; None if none."""
        return self._pending

    def update(
        self,
        key: tuple,
        static: StaticEnvironment,
        budget_ms: float | None,
        cube: moderngl.TextureCube | None = None,
    ) -> None:
        """Bring the set to ``key``, baking within ``budget_ms`` (None: all at once).

        Parameters
        ----------
        key
            (scene id, static revision, BRDF name, sorted bake values, map size,
            importance samples per lobe and texel).
        static
            The static environment the maps are baked from.
        budget_ms
            Milliseconds this call may bake for (at least one view), None for no limit.
        cube
            What the bake reads instead of the static environment's cube (samples 0:
            a map of E(n)/π, methods.rsibr.gpu_bake); cached under the static's key.
        """
        if key == self._key:
            self._pending = None
            return
        if self._pending is None or self._pending["key"] != key:
            self._start(key, static, cube)
        if self._pending is not None:
            self._continue(budget_ms)

    def generate(self, frame_d: np.ndarray, warp: str, **options) -> moderngl.Texture:
        """The generated map for destination frame ``frame_d`` (MapGenerator.generate)."""
        if self._generator is None or self._generator.size != self.bake.size:
            if self._generator is not None:
                self._generator.release()
            self._generator = MapGenerator(self.ctx, self.programs, self.bake.size)
        bake = self.bake
        return self._generator.generate(
            self.textures, bake.views, bake.frames, bake.faces, frame_d, warp, **options
        )

    @property
    def generator(self) -> MapGenerator | None:
        """The map generator of the last :meth:`generate` (its sources, accumulation)."""
        return self._generator

    def _start(
        self, key: tuple, static: StaticEnvironment, cube: moderngl.TextureCube | None
    ) -> None:
        env_key = self._env_keys.get(key[:2])
        if env_key is None:
            env_key = rb.environment_key(read_cube(static.cube, 0, self.programs))
            self._env_keys = {key[:2]: env_key}
        name, values, size, samples = key[2], dict(key[3]), key[4], key[5]
        path = rb.cache_dir() / rb.cache_key(env_key, name, values, size, 12, samples)
        self._pending = None
        if path.exists():
            try:
                self.last_bake_seconds = None
                self._install(rb.load_bake(path, size=size), key)
                return
            except InputFileError as error:  # refused: say so, bake it again
                print(f"envstudio: note: {error}; discarded, baking again", file=sys.stderr)
                discard(path)
        views, faces = rb.geodesic_views(12)
        self._pending = {
            "key": key,
            "path": path,
            "cube": static.cube if cube is None else cube,
            "env": env_key,
            "views": views,
            "faces": faces,
            "frames": np.stack([view_frame(v) for v in views]),
            "maps": [],
            "values": values,
            "start": time.perf_counter(),
        }

    def _continue(self, budget_ms: float | None) -> None:
        """Bake views until all are done or ``budget_ms`` is spent (at least one view)."""
        job = self._pending
        start = time.perf_counter()
        baker = GpuBaker(self.ctx, self.programs, job["key"][4])
        try:
            while len(job["maps"]) < len(job["views"]):
                frame = job["frames"][len(job["maps"])][None]
                name, samples = job["key"][2], job["key"][5]
                job["maps"].append(baker.bake(job["cube"], name, job["values"], frame, samples)[0])
                spent = 1e3 * (time.perf_counter() - start)
                more = len(job["maps"]) < len(job["views"])
                if more and budget_ms is not None and spent > budget_ms:
                    return
        finally:
            baker.release()
        bake = rb.RsibrBake(
            np.stack(job["maps"]),
            job["views"],
            job["frames"],
            job["faces"],
            job["key"][2],
            job["values"],
            job["key"][5],
            "gpu",
            job["env"],
        )
        self.last_bake_seconds = time.perf_counter() - job["start"]
        job["path"].parent.mkdir(parents=True, exist_ok=True)
        rb.save_bake(job["path"], bake)
        self._install(bake, job["key"])
        self._pending = None

    def _install(self, bake: rb.RsibrBake, key: tuple) -> None:
        self._release_textures()
        for image in bake.maps:
            tex = self.ctx.texture((bake.size, bake.size), 3, image.tobytes(), dtype="f4")
            tex.repeat_x = tex.repeat_y = False
            self.textures.append(tex)
        self.bake, self._key = bake, key

    def _release_textures(self) -> None:
        for tex in self.textures:
            tex.release()
        self.textures = []

    def release(self) -> None:
        """Free the textures and the generator; safe to call twice."""
        self._release_textures()
        if self._generator is not None:
            self._generator.release()
        self._generator = None
        self.bake = self._key = self._pending = None
