"""The Method panel's figure: the nearest view's maps (seed 003 Figure 5)."""

from __future__ import annotations

from collections.abc import Callable

import moderngl
import numpy as np

from envstudio.core.cubemap import faces_to_cross
from envstudio.methods.pem.bake.pem_file import PemBake
from envstudio.methods.pem.blending import ViewBlend
from envstudio.plugin import to_ldr, upright

__all__ = ["NearestViewFigure"]


class NearestViewFigure:
    """The first part's maps of the view weighted most, as RGBA8 textures it owns."""

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self._thumbnails: list[moderngl.Texture] = []

    def images(
        self,
        bake: PemBake,
        view_maps: Callable[[int], dict[str, list[np.ndarray]] | None],
        blend: ViewBlend,
        exposure: float,
        tonemap: str,
    ) -> list[tuple[str, moderngl.Texture]]:
        """Distant, local and sphere maps at level 0, then the distant map's levels 1–4.

        Parameters
        ----------
        bake
            The bake on show (its part names).
        view_maps
            A view's maps, model → levels of (P, 6, n_k, n_k, C) (None: not baked yet).
        blend
            The last frame's blend; its heaviest view is shown.
        exposure, tonemap
            The display's (stops, operator name).

        Returns
        -------
        list of (label, texture)
            Horizontal crosses, RGBA8 (local: colour over black); empty while the
            view is not baked.
        """
        view = blend.views[int(np.argmax(blend.weights))]
        maps = view_maps(view)
        if maps is None:
            return []
        images, labels = [], []
        for model in ("distant", "local", "sphere"):
            images.append(maps[model][0][0][..., :3])
            labels.append(f"{model}, level 0 (view {view}, {bake.parts[0]})")
        for level in range(1, min(5, len(maps["distant"]))):
            images.append(maps["distant"][level][0])
            labels.append(f"distant, level {level}")
        crosses = [upright(to_ldr(faces_to_cross(im), exposure, tonemap)) for im in images]
        if [t.size for t in self._thumbnails] != [c.shape[1::-1] for c in crosses]:
            self.release()
            self._thumbnails = [self.ctx.texture(c.shape[1::-1], 4) for c in crosses]
        for texture, rgb in zip(self._thumbnails, crosses, strict=True):
            alpha = np.full((*rgb.shape[:2], 1), 255, np.uint8)
            texture.write(np.ascontiguousarray(np.concatenate([rgb, alpha], axis=-1)).tobytes())
        return list(zip(labels, self._thumbnails, strict=True))

    def release(self) -> None:
        for texture in self._thumbnails:
            texture.release()
        self._thumbnails = []
