"""A few views of a large PEM on the GPU at a time: slots reused least recently first.

A full-orbit PEM (methods/pem/bake/orbit.py) has hundreds of views, far more
than one atlas holds (about 3 MB of float32 maps per view of two parts at 64²).
:class:`ResidentViews` keeps :data:`SLOTS` of them in atlases of the layout of
methods/pem/atlas.py (slot s is the shader's view s: its maps start at texel
s·P·T), with a copy in main memory from which the rows a slot covers are written
again when a view moves into it. Playback asks for the views it blends
(:meth:`ResidentViews.slots`); a view already resident costs nothing.
"""

from __future__ import annotations

import time
from collections import OrderedDict
from collections.abc import Callable

import moderngl
import numpy as np

from envstudio.methods.pem.atlas import ATLAS_WIDTH, flat_maps, pack_flags
from envstudio.methods.pem.bake.pem_file import PemBake
from envstudio.methods.pem.gpu import ATLASES

__all__ = ["SLOTS", "ResidentViews"]

#: Views resident at once: the 4 a grid blends, their neighbours, and room to turn back.
SLOTS = 16


class ResidentViews:
    """The atlases of :class:`~envstudio.methods.pem.gpu.PemTextures` for ``slots`` views.

    Parameters
    ----------
    ctx
        The context.
    shell
        The bake's geometry and parameters (``maps`` gives the shapes per view:
        (1, P, 6, n_k, n_k, C) per level).
    slots
        Views resident at once.

    Attributes
    ----------
    atlases, hull, hull_offsets, width, upload_ms
        As :class:`~envstudio.methods.pem.gpu.PemTextures` (``upload_ms``: the last
        view moved in).
    resident : OrderedDict of int to int
        View → slot, least recently used first.
    """

    def __init__(self, ctx: moderngl.Context, shell: PemBake, slots: int = SLOTS):
        self.width = min(ATLAS_WIDTH, int(ctx.info.get("GL_MAX_TEXTURE_SIZE", 4096)))
        self.slot_count = int(slots)
        self.models = [m for m in ATLASES if m in shell.maps]
        self._levels = {m: len(shell.maps[m]) for m in self.models}
        first = shell.maps[self.models[0]]
        self._parts = first[0].shape[1]
        self._texels = self._parts * sum(6 * a.shape[3] * a.shape[4] for a in first)  # P·T
        rows = -(-self._texels * self.slot_count // self.width)
        self._mirror = {m: np.zeros((rows * self.width, 4), np.float32) for m in self.models}
        self.atlases: dict[str, moderngl.Texture] = {}
        self.resident: OrderedDict[int, int] = OrderedDict()
        self.upload_ms = 0.0
        for model in self.models:
            texture = ctx.texture((self.width, rows), 4, dtype="f4")
            texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self.atlases[model] = texture
        flags, self.hull_offsets = pack_flags(shell.hull, self.width)
        self.hull = ctx.texture(
            (self.width, flags.shape[0]), 1, np.ascontiguousarray(flags).tobytes(), dtype="u1"
        )
        self.hull.filter = (moderngl.NEAREST, moderngl.NEAREST)

    @property
    def megabytes(self) -> float:
        """GPU memory of the atlases, MB."""
        return sum(t.width * t.height * 16 for t in self.atlases.values()) / 1e6

    def slots(
        self, views: list[int], load: Callable[[int], dict[str, list[np.ndarray]] | None]
    ) -> list[int] | None:
        """The slot of each view, moving in those not resident.

        Parameters
        ----------
        views
            View indices (at most ``slots`` distinct).
        load
            View → its maps (model → levels of (P, 6, n_k, n_k, C)), or None when it
            cannot be had (not baked yet).

        Returns
        -------
        list of int or None
            Slots in the order of ``views``; None when a view could not be loaded
            (those that could are resident).
        """
        for view in views:  # the views asked for are the most recently used
            if view in self.resident:
                self.resident.move_to_end(view)
        out = []
        for view in views:
            if view not in self.resident:
                maps = load(view)
                if maps is None:
                    return None
                self._move_in(view, maps)
            out.append(self.resident[view])
        return out

    def _move_in(self, view: int, maps: dict[str, list[np.ndarray]]) -> None:
        start = time.perf_counter()
        if len(self.resident) < self.slot_count:
            slot = len(self.resident)
        else:
            _, slot = self.resident.popitem(last=False)
        lo, hi = slot * self._texels, (slot + 1) * self._texels
        r0, r1 = lo // self.width, -(-hi // self.width)
        for model in self.models:
            levels = [np.asarray(a)[None] for a in maps[model][: self._levels[model]]]
            self._mirror[model][lo:hi] = flat_maps(levels)
            rows = self._mirror[model][r0 * self.width : r1 * self.width]
            self.atlases[model].write(rows.tobytes(), viewport=(0, r0, self.width, r1 - r0))
        self.resident[view] = slot
        self.upload_ms = (time.perf_counter() - start) * 1e3

    def release(self) -> None:
        """Free the textures; safe to call twice."""
        for texture in self.atlases.values():
            texture.release()
        self.atlases = {}
        if getattr(self, "hull", None) is not None:
            self.hull.release()
            self.hull = None
