"""GPU copies of an environment's luminance-sampling tables, for the estimator's shader."""

from __future__ import annotations

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.env_sampling import EnvironmentDistribution
from envstudio.plugin import set_uniform


class EnvironmentTables:
    """The luminance-sampling tables of one environment as R32F textures.

    Parameters
    ----------
    ctx : moderngl.Context
        Where the textures live.
    radiance : (h, w, 3) float32
        The lat-long environment's linear radiance.
    """

    def __init__(self, ctx: moderngl.Context, radiance: npt.NDArray[np.float32]):
        dist = EnvironmentDistribution.from_latlong(radiance)
        h, w = dist.shape
        p_uv = dist.weights / dist.weights.sum() * (w * h)
        self.textures = [
            _r32f_texture(ctx, dist.marginal_cdf[None, :]),
            _r32f_texture(ctx, dist.conditional_cdf),
            _r32f_texture(ctx, p_uv),
        ]

    def bind(self, program: moderngl.Program, first_unit: int) -> None:
        """Bind the marginal CDF, the conditional CDFs and the pdf over (u, v) to ``program``
        at texture units ``first_unit`` … ``first_unit`` + 2."""
        for offset, (name, tex) in enumerate(
            zip(("u_env_marginal", "u_env_conditional", "u_env_pdf_uv"), self.textures, strict=True)
        ):
            tex.use(location=first_unit + offset)
            set_uniform(program, name, first_unit + offset)

    def release(self) -> None:
        """Free the textures; safe to call twice."""
        for tex in self.textures:
            tex.release()
        self.textures = []


def _r32f_texture(ctx: moderngl.Context, array: npt.ArrayLike) -> moderngl.Texture:
    """A nearest-filtered one-channel float texture of the (h, w) ``array``."""
    data = np.ascontiguousarray(array, dtype=np.float32)
    tex = ctx.texture((data.shape[1], data.shape[0]), 1, data.tobytes(), dtype="f4")
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return tex
