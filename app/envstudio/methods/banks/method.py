"""Method ``banks``: anisotropic prefiltered environment maps with the Banks model (seed 004 §5.3).

Once per change of the static environment (GpuScene.static_environment: the
local objects over the far field, seen from the reflector), of s or of the
resolution, the 3D map L_banks(t, ⟨v,t⟩) is built (methods/banks/maps.py: on the
GPU by two compute passes, or in NumPy with ``builder=cpu`` or on contexts older
than OpenGL 4.3); a change of s alone reuses the ring table and redoes only the
cheap second pass. The reflector then looks the map up with the tangent of the
material's tangent field (scene/tangents.py) and the view, per vertex or per
pixel, and combines it with Fresnel and Miller's diffuse map (seed 004 §4,
shading/miller_map.py) by seed 004 eq. 2 with seed 000's Schlick weights
(shaders/banks/banks.glsl). ``view=slice`` shows one slice of the map at
∠(v, t) = ``slice_angle`` as the frame (seed 004 Figure 6, right).

The self-shadowing term ⟨n,l⟩ is dropped, as the paper does: the map reflects
light from behind the surface ("usually not noticeable unless a bright light
source shines through", §5.3); ``reference`` with model=banks and
``self_shadowing`` measures what that costs.
"""

from __future__ import annotations

import time

import moderngl

from envstudio.envmap.conversions import read_cube
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.methods.banks.maps import GpuMapBuilder, MapSpec, build_cpu, map_texture, upload
from envstudio.plugin import (
    EQ8_PARAMETERS,
    FrameInputs,
    Method,
    MillerDiffuseMap,
    Parameter,
    ParameterError,
    set_eq8_uniforms,
    set_uniform,
)
from envstudio.scene.tangents import TangentField
from envstudio.shading.materials import BANKS_MATERIAL_PARAMETERS
from envstudio.shading.tangent_buffers import TangentBuffers

VIEWS = ("reflector", "slice")
BUILDERS = ("gpu", "cpu")


class BanksMethod(Method):
    """Banks-model anisotropic 3D environment map (seed 004 §5.3)."""

    name = "banks"
    paper = "Kautz, Vázquez, Heidrich, Seidel 2000, §5.3 (seed 004)"
    reflectance = "banks"
    title = "Kautz et al. 2000 (anisotropic Banks map, 3D texture)"
    summary = (
        "3D map L_banks(t, ⟨v,t⟩) indexed by the tangent (front paraboloid, folded by "
        "symmetry) and ∠(v,t); per-vertex or per-pixel coordinates; Schlick Fresnel."
    )
    parameters = (
        *BANKS_MATERIAL_PARAMETERS,
        Parameter(
            "per_pixel",
            "bool",
            False,
            help="Tangent and ⟨v,t⟩ per pixel; off: per vertex and interpolated (the paper).",
        ),
        Parameter(
            "map_size",
            "int",
            64,
            8,
            1024,
            "texels",
            "Texels across the tangent face (2 of border on each side).",
        ),
        Parameter("slices", "int", 64, 2, 1024, "", "Slices in ∠(v,t) ∈ [0°, 180°]."),
        Parameter(
            "bins",
            "int",
            128,
            4,
            2048,
            "",
            "Ring bins in ∠(l,t) ∈ [0°, 180°] (2 × bins samples per ring); the environment "
            "is read at the mip level whose texels are one bin wide.",
        ),
        Parameter(
            "builder",
            "choice",
            "gpu",
            choices=BUILDERS,
            help="Build the map with compute shaders, or in NumPy (the test path; also used "
            "without OpenGL 4.3).",
        ),
        Parameter(
            "view",
            "choice",
            "reflector",
            choices=VIEWS,
            help="The reflector, or one slice of the 3D map as the frame.",
        ),
        Parameter(
            "slice_angle",
            "float",
            44.0,
            0.0,
            180.0,
            "deg",
            "∠(v,t) of the slice shown by view=slice (seed 004 Figure 6: 44, 39, 35).",
        ),
        *EQ8_PARAMETERS,  # fresnel f_λ and k_d: the same eq. 8 as mirror's
    )

    def __init__(self, ctx: moderngl.Context, programs):
        super().__init__(ctx, programs)
        self.builder = GpuMapBuilder(ctx, programs)
        self.tangent_buffers = TangentBuffers(ctx)
        self._quad = FullscreenPass(ctx)
        self._diffuse = MillerDiffuseMap(ctx, programs)
        self._map: moderngl.Texture3D | None = None
        self._map_key: tuple | None = None
        #: Map builds so far, and the seconds the last one took (bench, tests).
        self.builds = 0
        self.last_build_s = 0.0
        #: Why a tangent field fell back (shown by the UI's status line); empty if none.
        self.notes: list[str] = []

    def spec(self) -> MapSpec:
        """The map the current values ask for."""
        v = self.values
        return MapSpec(int(v["map_size"]), int(v["slices"]), int(v["bins"]), float(v["sharpness"]))

    def field(self) -> TangentField:
        """The tangent field of the current values."""
        return TangentField(str(self.values["tangent_field"]), str(self.values["tangent_axis"]))

    def status_line(self) -> str:
        """The tangent-field fallback notes, if any."""
        return "; ".join(self.notes)

    def map_texture(self, frame: FrameInputs) -> moderngl.Texture3D:
        """The 3D map for this frame's static environment, (re)built if needed."""
        static = frame.scene.static_environment(frame.timer)
        spec = self.spec()
        use_gpu = self.values["builder"] == "gpu" and self.ctx.version_code >= 430
        key = (id(frame.scene), static.revision, spec, use_gpu)
        if key == self._map_key:
            return self._map
        previous = self._map_key
        if self._map is None or self._map.size != (spec.size, spec.size, spec.slices):
            self._release_map()
            self._map = map_texture(self.ctx, spec)
        if use_gpu:
            same_rings = (
                previous is not None
                and previous[:2] == key[:2]
                and previous[3]
                and (previous[2].size, previous[2].bins) == (spec.size, spec.bins)
            )
            self.builder.build(static.cube, spec, self._map, frame.timer, rings_valid=same_rings)
            self.last_build_s = self.builder.last_build_s
        else:
            start = time.perf_counter()
            with frame.timer.measure("banks.cpu"):
                values = build_cpu(read_cube(static.cube), spec)
                self._release_map()
                self._map = upload(self.ctx, spec, values)
            self.last_build_s = time.perf_counter() - start
        self._map_key = key
        self.builds += 1
        return self._map

    def render(self, frame: FrameInputs) -> None:
        texture = self.map_texture(frame)
        frame.target.use()
        normalise = bool(self.values["normalize"])
        if self.values["view"] == "slice":
            program = self.programs.get("banks/slice.glsl")
            texture.use(location=0)
            set_uniform(program, "u_map", 0)
            set_uniform(program, "u_w", float(self.values["slice_angle"]) / 180.0)
            set_uniform(program, "u_normalise", normalise)
            with frame.timer.measure("banks"):
                self.ctx.disable(moderngl.DEPTH_TEST)
                self._quad.draw(program)
                self.ctx.enable(moderngl.DEPTH_TEST)
            return
        program = self.programs.get("banks/banks.glsl")
        texture.use(location=0)
        self._diffuse.update(frame, "banks").use(location=1)
        set_uniform(program, "u_map", 0)
        set_uniform(program, "u_diffuse_map", 1)
        set_uniform(program, "u_map_size", float(texture.size[0]))
        set_uniform(program, "u_per_pixel", bool(self.values["per_pixel"]))
        set_uniform(program, "u_normalise", normalise)
        set_eq8_uniforms(program, frame, self.values)
        set_uniform(program, "u_view", frame.view)
        set_uniform(program, "u_projection", frame.projection)
        field = self.field()
        reflectors = frame.scene.reflectors()
        self.tangent_buffers.forget_unused(reflectors)
        self.notes = sorted(
            {self.tangent_buffers.tangents(g, field).note for g in reflectors} - {""}
        )
        # The window gives every method a frame budget and shows the notes in the panel
        # (status_line); headless (no budget) a fallback is the command's one-line error.
        if self.notes and self.frame_budget_ms is None:
            raise ParameterError(f"tangent_field={field.kind}: {self.notes[0]}")
        with frame.timer.measure("banks"):
            for gpu_node in reflectors:
                set_uniform(program, "u_model", gpu_node.model)
                set_uniform(program, "u_normal_matrix", gpu_node.normal)
                self.tangent_buffers.render(program, gpu_node, field)

    def _release_map(self) -> None:
        if self._map is not None:
            self._map.release()
        self._map = None
        self._map_key = None

    def release(self) -> None:
        """Free the map, its builder, the tangent buffers and vertex arrays; safe twice."""
        self._release_map()
        self.builder.release()
        self.tangent_buffers.release()
        self._diffuse.release()
        self._quad.release()
