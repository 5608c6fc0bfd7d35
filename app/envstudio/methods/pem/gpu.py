"""A loaded PEM bake on the GPU: the atlases, the hull flags and the EM geometry."""

from __future__ import annotations

import time

import moderngl
import numpy as np

from envstudio.methods.pem.atlas import ATLAS_WIDTH, pack_atlas, pack_flags
from envstudio.methods.pem.bake.pem_file import PemBake
from envstudio.plugin import InputFileError

__all__ = ["ATLASES", "MODELS", "TEXGENS", "PemTextures", "texgen_defines"]

#: EM models of the panel's switch, in the shader's ``u_em_model`` order: seed 003's
#: layered PEM, sphere at infinity (Figure 6), static EM (Figure 1c) and PTM (Figure 7,
#: a bake's per-view surface textures as a polynomial in the view; issue 31).
MODELS = ("layered", "sphere", "static", "ptm")
#: The bake's maps each atlas holds (``ptm`` only for bakes that have it).
ATLASES = ("distant", "local", "sphere", "ptm")
#: Where the lookup vectors are computed: per fragment, or per vertex (seed 003 §4).
TEXGENS = ("fragment", "vertex")


def texgen_defines(texgen: str) -> dict[str, int]:
    """The defines of shaders/pem/pem.glsl for a texgen mode of :data:`TEXGENS`."""
    if texgen not in TEXGENS:
        raise ValueError(f"texgen {texgen!r}: expected one of {', '.join(TEXGENS)}")
    return {"PEM_TEXGEN_VERTEX": 1} if texgen == "vertex" else {}


class PemTextures:
    """GPU copies of a bake's maps: one atlas per model, every view resident.

    Parameters
    ----------
    ctx
        The context.
    bake
        A verified bake (:func:`envstudio.methods.pem.bake.load_pem`).

    Attributes
    ----------
    atlases : dict of str to moderngl.Texture
        ``distant``, ``local``, ``sphere`` and, where baked, ``ptm``: RGBA32F atlases
        (methods/pem/atlas.py).
    hull : moderngl.Texture
        R8UI per-triangle convex-hull flags of every part.
    hull_offsets : list of int
        First flag of each part.
    upload_ms : float
        Wall time of the uploads, ms (the cost of a bake switch, paid once).
    """

    def __init__(self, ctx: moderngl.Context, bake: PemBake):
        start = time.perf_counter()
        limit = int(ctx.info.get("GL_MAX_TEXTURE_SIZE", 4096))
        self.width = min(ATLAS_WIDTH, limit)
        self.atlases: dict[str, moderngl.Texture] = {}
        try:
            for model in (m for m in ATLASES if m in bake.maps):
                image = pack_atlas(bake.maps[model], self.width)
                if image.shape[0] > limit:
                    raise InputFileError(
                        f"{bake.header.get('path', 'the .pem')}: {model} maps need an atlas of "
                        f"{image.shape[0]} rows, this GL allows {limit}: bake fewer views or "
                        "a smaller --em-size"
                    )
                texture = ctx.texture((self.width, image.shape[0]), 4, image.tobytes(), dtype="f4")
                texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
                self.atlases[model] = texture
            flags, self.hull_offsets = pack_flags(bake.hull, self.width)
            self.hull = ctx.texture(
                (self.width, flags.shape[0]), 1, np.ascontiguousarray(flags).tobytes(), dtype="u1"
            )
            self.hull.filter = (moderngl.NEAREST, moderngl.NEAREST)
        except BaseException:
            self.release()
            raise
        ctx.finish()
        self.upload_ms = (time.perf_counter() - start) * 1e3

    @property
    def megabytes(self) -> float:
        """GPU memory of the atlases, MB."""
        return sum(t.width * t.height * 16 for t in self.atlases.values()) / 1e6

    def release(self) -> None:
        """Free the textures; safe to call twice."""
        for texture in self.atlases.values():
            texture.release()
        self.atlases = {}
        hull = getattr(self, "hull", None)
        if hull is not None:
            hull.release()
            self.hull = None
