"""GPU bake of radiance sphere maps: shaders/rsibr/bake.glsl, one fragment pass per view.

The environment is a mipmapped cube map (envmap.conversions.latlong_to_cube, or
a method's ``GpuScene.static_environment().cube``); each view's map is rendered
into an (n, n) RGBA32F target and read back. See the shader for the estimator.
"""

from __future__ import annotations

from collections.abc import Callable

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.envmap.conversions import read_texture
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.gpu.programs import ProgramLibrary
from envstudio.methods.rsibr.bake.bake import RsibrBake, geodesic_views
from envstudio.methods.rsibr.bake.brdfs import brdf
from envstudio.methods.rsibr.warp import view_frame
from envstudio.plugin import set_uniform

__all__ = ["DEFAULT_SAMPLES", "GpuBaker", "bake_gpu"]

#: Importance samples per lobe and texel (filtered importance sampling converges with few).
DEFAULT_SAMPLES = 256
_PROGRAM = "rsibr/bake.glsl"


class GpuBaker:
    """Renders radiance sphere maps from a cube map; owns its target.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    size
        Map edge n in texels.
    """

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary, size: int):
        self.ctx = ctx
        self.programs = programs
        self.size = size
        self.texture = ctx.texture((size, size), 4, dtype="f4")
        self.framebuffer = ctx.framebuffer(color_attachments=[self.texture])
        self._pass = FullscreenPass(ctx)

    def render(
        self,
        cube: moderngl.TextureCube,
        name: str,
        values: dict[str, float],
        frame: npt.ArrayLike,
        samples: int = DEFAULT_SAMPLES,
    ) -> None:
        """Draw one view's map into :attr:`texture` (the caller's framebuffer stays bound).

        Parameters
        ----------
        cube
            Environment cube map with its mip chain.
        name, values
            BRDF name and every parameter (bake.rsibr.brdfs).
        frame : (3, 3) float
            The view's camera frame T_j.
        samples
            Importance samples per lobe and texel; 0 for ``lambertian`` from a cube
            that holds E(n)/π already (Miller's map): each texel reads it along n.
        """
        spec = brdf(name)
        program = self.programs.get(_PROGRAM)
        cube.use(location=0)
        set_uniform(program, "u_environment", 0)
        set_uniform(program, "u_cube_size", float(cube.size[0]))
        set_uniform(program, "u_frame", np.asarray(frame, dtype=np.float32))
        set_uniform(program, "u_brdf", spec.code)
        # samples 0: the cube holds E(n)/pi already (shading/miller_map.py), read along n
        set_uniform(program, "u_samples", max(int(samples), 1))
        set_uniform(program, "u_irradiance_cube", int(samples) == 0)
        set_uniform(program, "u_phong_exponent", values.get("phong_exponent", 1.0))
        set_uniform(program, "u_coat_f0", values.get("coat_f0", 0.0))
        set_uniform(program, "u_base_exponent", values.get("base_exponent", 1.0))
        set_uniform(program, "u_metallic", values.get("metallic", 0.0))
        paint = [values.get(k, 0.0) for k in ("paint_red", "paint_green", "paint_blue")]
        set_uniform(program, "u_paint", tuple(paint))
        # a scope restores the caller's framebuffer and flags: a released baker must not
        # stay bound, or the next scope elsewhere rebinds a deleted framebuffer
        scope = self.ctx.scope(self.framebuffer, enable_only=moderngl.NOTHING)
        try:
            with scope:
                self._pass.draw(program)
        finally:
            scope.release()

    def bake(
        self,
        cube: moderngl.TextureCube,
        name: str,
        values: dict[str, float],
        frames: npt.ArrayLike,
        samples: int = DEFAULT_SAMPLES,
        progress: Callable[[int], None] | None = None,
    ) -> npt.NDArray[np.float32]:
        """Every view's map, read back.

        Parameters
        ----------
        frames : (V, 3, 3) float
            Camera frames of the views.
        progress
            Called with the number of texels finished after each view.

        Returns
        -------
        (V, n, n, 3) float32
            Linear radiance, core.spheremap layout.
        """
        maps = []
        for frame in np.asarray(frames):
            self.render(cube, name, values, frame, samples)
            maps.append(read_texture(self.texture))
            if progress is not None:
                progress(self.size * self.size)
        return np.stack(maps)

    def release(self) -> None:
        """Free the target and the pass; safe to call twice."""
        self._pass.release()
        for obj in (self.framebuffer, self.texture):
            if obj is not None:
                obj.release()
        self.framebuffer = self.texture = None


def bake_gpu(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    cube: moderngl.TextureCube,
    environment: str,
    name: str,
    values: dict[str, object] | None = None,
    size: int = 64,
    views: int = 12,
    samples: int = DEFAULT_SAMPLES,
    progress: Callable[[int], None] | None = None,
) -> RsibrBake:
    """Every view's map on the GPU.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    cube
        Mipmapped environment cube map.
    environment
        Key of the environment (bake.rsibr.bake.environment_key).
    name, values
        BRDF and its parameters (validated; defaults for the rest).
    size, views, samples
        Map edge, 12 or 42 views, importance samples per lobe.
    progress
        Called with texels finished.
    """
    params = brdf(name).values(values)
    vertices, faces = geodesic_views(views)
    frames = np.stack([view_frame(v) for v in vertices])
    baker = GpuBaker(ctx, programs, size)
    try:
        maps = baker.bake(cube, name, params, frames, samples, progress)
    finally:
        baker.release()
    return RsibrBake(maps, vertices, frames, faces, name, params, samples, "gpu", environment)
