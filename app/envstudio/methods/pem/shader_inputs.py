"""The textures and uniforms of shaders/pem/pem.glsl for one frame."""

from __future__ import annotations

import moderngl
import numpy as np

from envstudio.methods.pem.bake.pem_file import PemBake
from envstudio.methods.pem.blending import ViewBlend
from envstudio.methods.pem.gpu import ATLASES, MODELS, PemTextures
from envstudio.methods.pem.resident import ResidentViews
from envstudio.plugin import FrameInputs, ParameterValues, set_uniform

__all__ = ["MAX_BLENDED", "PemShaderInputs"]

#: Length of the shader's ``u_view_map`` and ``u_view_weight`` arrays.
MAX_BLENDED = 16
#: Texture units of the atlases (in :data:`~envstudio.methods.pem.gpu.ATLASES` order);
#: the static EM is on 0, the hull flags on 4.
_ATLAS_UNITS = (1, 2, 3, 5)


class PemShaderInputs:
    """Binds a bake's maps, the layer switches and the blend; 1 x 1 stand-in textures
    while no bake is loaded (owned here, freed by :meth:`release`)."""

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self._stand_ins: dict[str, moderngl.Texture] = {}

    def _stand_in_textures(self) -> dict[str, moderngl.Texture]:
        """``atlas``: one RGBA32F texel of zeros; ``hull``: one R8UI flag of 0."""
        if not self._stand_ins:
            zero = np.zeros(4, np.float32).tobytes()
            self._stand_ins = {
                "atlas": self.ctx.texture((1, 1), 4, zero, dtype="f4"),
                "hull": self.ctx.texture((1, 1), 1, b"\0", dtype="u1"),
            }
            for texture in self._stand_ins.values():
                texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
        return self._stand_ins

    def bind_maps(
        self,
        program: moderngl.Program,
        static_cube: moderngl.TextureCube,
        textures: PemTextures | ResidentViews | None,
    ) -> None:
        """The static EM, the atlases and the hull flags of ``textures`` (None: stand-ins)."""
        static_cube.use(location=0)
        set_uniform(program, "u_static", 0)
        stand_in = self._stand_in_textures()
        atlases = {} if textures is None else textures.atlases
        for unit, model in zip(_ATLAS_UNITS, ATLASES, strict=True):
            atlases.get(model, stand_in["atlas"]).use(location=unit)
            set_uniform(program, f"u_{model}", unit)
        (stand_in["hull"] if textures is None else textures.hull).use(location=4)
        set_uniform(program, "u_hull", 4)

    @staticmethod
    def set_layers(program: moderngl.Program, frame: FrameInputs, values: ParameterValues) -> None:
        """The camera, the SH9 irradiance and the layer switches, Fresnel f_λ and k_d."""
        set_uniform(program, "u_camera_position", frame.camera_position)
        set_uniform(program, "u_view", frame.view)
        set_uniform(program, "u_projection", frame.projection)
        set_uniform(program, "u_sh9", frame.scene.sh9)
        set_uniform(program, "u_fresnel", tuple(values["fresnel"]))
        set_uniform(program, "u_kd", tuple(values["kd"]))
        for name in ("distant", "local", "diffuse", "hull"):
            set_uniform(program, f"u_use_{name}", bool(values[name]))
        set_uniform(program, "u_use_fresnel", bool(values["fresnel_layer"]))

    @staticmethod
    def show_static(program: moderngl.Program) -> None:
        """Draw the static EM (no bake, or its views not baked yet), no hull."""
        set_uniform(program, "u_em_model", MODELS.index("static"))
        set_uniform(program, "u_use_hull", False)

    @staticmethod
    def set_bake(
        program: moderngl.Program,
        frame: FrameInputs,
        bake: PemBake,
        textures: PemTextures | ResidentViews,
        lod_scale: str,
    ) -> None:
        """The bake's parts, atlas layout, EM size and levels, box, and the MIP bias.

        ``lod_scale`` ``bake`` adds log2 of this image's height over the bake's
        image size ``R``, as if the frame had the bake's R x R footprint.
        """
        set_uniform(program, "u_parts", len(bake.parts))
        set_uniform(program, "u_atlas_width", textures.width)
        set_uniform(program, "u_hull_width", textures.width)
        set_uniform(program, "u_em_size", bake.em_size)
        set_uniform(program, "u_em_levels", len(bake.maps["distant"]))
        bias = float(bake.parameters.get("lod_bias", 0.0))
        if lod_scale == "bake":  # the footprint the bake's R x R image had
            bias += float(
                np.log2(frame.size[1] / float(bake.parameters.get("size", frame.size[1])))
            )
        set_uniform(program, "u_lod_bias", bias)
        set_uniform(program, "u_box_lo", bake.box[0])
        set_uniform(program, "u_box_hi", bake.box[1])

    @staticmethod
    def set_blend(program: moderngl.Program, blend: ViewBlend, views: list[int]) -> None:
        """The blend's weights and the atlas slot of each of its ``views``."""
        views = views + [0] * (MAX_BLENDED - len(views))
        weights = list(blend.weights) + [0.0] * (MAX_BLENDED - len(blend.weights))
        set_uniform(program, "u_view_map", tuple(int(v) for v in views))  # int[16]
        set_uniform(program, "u_view_weight", tuple(float(w) for w in weights))
        set_uniform(program, "u_views_blended", len(blend.views))

    def release(self) -> None:
        for texture in self._stand_ins.values():
            texture.release()
        self._stand_ins = {}
