"""A ``.pem`` bake file on show: its maps uploaded whole, or streamed view by view.

A file of at most :data:`~envstudio.methods.pem.resident.SLOTS` views is uploaded
once (methods/pem/gpu.py); a larger one (the paper's 100 views at 256²: 4.2 GB of
float32 maps) keeps a few views resident and moves in the ones a frame blends
(methods/pem/resident.py).
"""

from __future__ import annotations

import sys
from pathlib import Path

import moderngl
import numpy as np

from envstudio.methods.pem.bake.pem_file import PemBake
from envstudio.methods.pem.blending import ViewBlend
from envstudio.methods.pem.gpu import PemTextures
from envstudio.methods.pem.resident import SLOTS, ResidentViews
from envstudio.scene.graph import Scene

__all__ = ["FilePlayback", "environment_note"]


class FilePlayback:
    """A verified bake file's maps on the GPU, and which atlas slots a blend's views are in.

    Parameters
    ----------
    ctx
        The context.
    bake
        A bake verified against the scene (methods/pem/verify.py).
    path
        Its file (for messages and bench notes).
    key
        What the method keeps it loaded for (the file, scene, meshes and coverage).
    models
        The reflectors' 4 x 4 model matrices it is played for, one per part.

    Raises
    ------
    InputFileError
        The bake does not fit this GL's textures.
    """

    def __init__(
        self,
        ctx: moderngl.Context,
        bake: PemBake,
        path: Path,
        key: tuple,
        models: list[np.ndarray],
    ):
        streamed = bake.views > SLOTS  # a few resident, moved in as blended (the orbit's way)
        self.textures = ResidentViews(ctx, bake) if streamed else PemTextures(ctx, bake)
        self.key = key
        self.path = path
        self.bake = bake
        self.models = models

    def view_maps(self, view: int) -> dict[str, list[np.ndarray]]:
        """One view's maps: model → levels of (P, 6, n_k, n_k, C) float32 arrays."""
        return {m: [level[view] for level in levels] for m, levels in self.bake.maps.items()}

    def place(self, blend: ViewBlend) -> tuple[ViewBlend, list[int]]:
        """``blend`` and the shader's view index (atlas slot) of each of its views.

        A streamed file moves the views not resident into slots first.
        """
        if isinstance(self.textures, ResidentViews):
            return blend, self.textures.slots(list(blend.views), self.view_maps)
        return blend, list(blend.views)

    def residency_line(self, blend: ViewBlend) -> str:
        """The status line: views and MB resident, the upload time, the views blended."""
        bake, textures = self.bake, self.textures
        pairs = zip(blend.views, blend.weights, strict=True)
        views = " + ".join(f"{v} ({w:.2f})" for v, w in pairs)
        if isinstance(textures, ResidentViews):
            return (
                f"{len(textures.resident)} of {bake.views} views x {len(bake.parts)} parts "
                f"resident ({textures.megabytes:.1f} MB; the last moved in in "
                f"{textures.upload_ms:.0f} ms); blending views {views}"
            )
        return (
            f"{bake.views} views x {len(bake.parts)} parts resident ({textures.megabytes:.1f} "
            f"MB, uploaded in {textures.upload_ms:.0f} ms); blending views {views}"
        )

    def bench_notes(self, blended: int) -> dict:
        """Views resident, texture MB, upload ms, and ``blended``: the views the last frame
        blended."""
        textures = self.textures
        if isinstance(textures, ResidentViews):  # a large file, streamed
            return {
                "bake": str(self.path),
                "views_resident": len(textures.resident),
                "texture_mb": round(textures.megabytes, 2),
                "view_switch_upload_ms": round(textures.upload_ms, 2),
                "views_blended": blended,
            }
        return {
            "bake": str(self.path),
            "views_resident": self.bake.views,
            "texture_mb": round(textures.megabytes, 2),
            "upload_ms_once": round(textures.upload_ms, 2),
            "view_switch_upload_ms": 0.0,
            "views_blended": blended,
        }

    def release(self) -> None:
        self.textures.release()


def environment_note(bake: PemBake, scene: Scene, path: Path) -> str:
    """A warning when ``bake`` records another environment than the scene's (else "").

    A bake holds the far field it was traced under; played under another map it
    shows the old one. Bakes made before the record are taken as they are. The
    warning is also printed to stderr.
    """
    recorded = bake.parameters.get("environment")
    if recorded is None or recorded == scene.environment.checksum():
        return ""
    note = (
        f"{path.name} was baked under another environment than {scene.environment.name}: "
        "its maps show that one; bake again for this map"
    )
    print(f"envstudio: warning: {note}", file=sys.stderr)
    return note
