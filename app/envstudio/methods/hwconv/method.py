"""Method ``hwconv``: hardware-accelerated Phong prefiltering of seed 004 §5.2.

Every refilter (once per change of the environment or of a filter parameter, or
every frame with ``refilter_every_frame``, as in the paper's timing table):

1. the static environment (GpuScene.static_environment: the local objects over the
   far field, seen from the reflector) is resampled into a dual paraboloid with a
   border and its mip chain (only when that environment, ``map_size`` or ``border``
   changes);
2. radii.plan_filters gives r_s, r_l and the shrink factors from N, ε and the
   maximum kernel size;
3. convolution.ParaboloidConvolution convolves both faces with the Phong lobe
   sampled in paraboloid space at the centre (map S) and at the rim (map L), each
   at its shrunk mip level, and blends them with weight d² (skipped in ``one_pass``);

then the reflector reads the result along the reflection vector and combines it
with Miller's diffuse map indexed by the normal (seed 004 §4, shading/miller_map.py)
by seed 004 eq. 2 with seed 000's Schlick weights (shaders/hwconv/hwconv.glsl). N and ε only
change the kernel weights, uniforms of one compiled program: no recompile.
``view`` shows S, L, the blended map or the source as the frame instead.

In ``envstudio compare``'s report (:meth:`HwConvMethod.report_extras`) the method
adds its accuracy against the brute-force Phong prefilter at the compared N
(methods/hwconv/accuracy.py at a cheap setting: :data:`REPORT_DIRECTIONS`
directions, error image faces of :data:`REPORT_FACE` texels), a table and the
error image.
"""

from __future__ import annotations

from pathlib import Path

import moderngl

from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.methods.hwconv.convolution import FaceMaps, ParaboloidConvolution
from envstudio.methods.hwconv.radii import MAX_KERNEL, FilterPlan, plan_filters
from envstudio.plugin import (
    EQ8_PARAMETERS,
    FrameInputs,
    Method,
    MillerDiffuseMap,
    Parameter,
    ParameterError,
    ReportExtra,
    set_uniform,
)

#: Choices of ``view``: the reflector, or one of the maps as the frame.
VIEWS = ("reflector", "blended", "small", "large", "exact")
#: Choices of ``kernel``: the paper's two shift-invariant maps, or the exact shift-variant one.
KERNELS = ("two_maps", "exact")
#: Lookup directions of the accuracy compare's report adds (a few seconds).
REPORT_DIRECTIONS = 2048
#: Texels across each face's disc in the error image compare's report adds.
REPORT_FACE = 128


class HwConvMethod(Method):
    """Two-pass hardware Phong convolution of a dual-paraboloid map (seed 004 §5.2)."""

    name = "hwconv"
    paper = "Kautz, Vázquez, Heidrich, Seidel 2000, §5.2 (seed 004)"
    title = "Kautz et al. 2000 (hardware Phong prefilter, dual paraboloid)"
    summary = (
        "Dual-paraboloid map convolved on the GPU with the Phong lobe at the centre (S) "
        "and rim (L) radii, shrunk through the mip chain, blended by d²; Schlick Fresnel."
    )
    parameters = (
        Parameter(
            "phong_exponent",
            "float",
            100.0,
            1.0,
            10000.0,
            "N",
            "Phong exponent of the lobe ⟨r, l⟩^N the map is convolved with.",
            log=True,
        ),
        Parameter(
            "epsilon",
            "float",
            0.1,
            0.001,
            0.99,
            "ε",
            "Lobe values below ε are clamped to zero, which bounds the kernel (paper: 0.1).",
            log=True,
        ),
        Parameter(
            "max_kernel",
            "int",
            7,
            1,
            MAX_KERNEL,
            "texels",
            "Largest filter size; larger kernels shrink map and filter by 2 (paper: 7, SGI O2).",
        ),
        Parameter(
            "map_size",
            "int",
            128,
            8,
            65536,
            "texels",
            "Texels across each paraboloid face's unit disc (paper: 512).",
        ),
        Parameter(
            "border",
            "int",
            36,
            0,
            65536,
            "texels",
            "Border outside the disc on each side of a face; must hold the largest kernel's "
            "radius (paper: 64).",
        ),
        Parameter(
            "kernel",
            "choice",
            "two_maps",
            choices=KERNELS,
            help="two_maps: S and L blended by d² (the paper); exact: the Phong lobe per texel "
            "with the paraboloid's solid angle, a shift-variant kernel (past the paper).",
        ),
        Parameter(
            "one_pass",
            "bool",
            False,
            help="Only the small kernel (map S), the paper's 1-pass column.",
        ),
        Parameter(
            "refilter_every_frame",
            "bool",
            False,
            help="Convolve again every frame even when nothing changed (the paper's timings).",
        ),
        Parameter(
            "view",
            "choice",
            "reflector",
            choices=VIEWS,
            help="Show the reflector, or the blended map, S, L or the exact map as the frame "
            "(front | back).",
        ),
        *EQ8_PARAMETERS,  # fresnel f_λ and k_d: the same eq. 8 as mirror's
    )

    def __init__(self, ctx: moderngl.Context, programs):
        super().__init__(ctx, programs)
        self.convolution = ParaboloidConvolution(ctx, programs)
        self._quad = FullscreenPass(ctx)
        self._source_key: tuple | None = None
        self._filter_key: tuple | None = None
        self._result: FaceMaps | None = None
        self._diffuse = MillerDiffuseMap(ctx, programs)
        #: Convolutions run so far (tests and the bench count refilters).
        self.refilters = 0

    def plan(self) -> FilterPlan:
        """The kernels of the current values; raises ParameterError for a bad combination.

        Checks the faces against the context's GL_MAX_TEXTURE_SIZE and the border
        against the largest kernel's radius (radii.FilterPlan.check_border).
        """
        values = self.values
        size, border = int(values["map_size"]), int(values["border"])
        limit = int(self.ctx.info["GL_MAX_TEXTURE_SIZE"])
        if size + 2 * border > limit:
            faces = (
                f"(faces of map_size + 2·border={size + 2 * border} texels exceed "
                f"GL_MAX_TEXTURE_SIZE={limit})"
            )
            if size <= limit - 2 * 8:  # the map fits: the border is what is too large
                raise ParameterError(
                    f"border={border}: expected an integer in [0, {(limit - size) // 2}] {faces}"
                )
            raise ParameterError(
                f"map_size={size}: expected an integer in [8, {max(limit - 2 * border, 8)}] {faces}"
            )
        plan = plan_filters(
            float(values["phong_exponent"]),
            float(values["epsilon"]),
            size,
            border,
            int(values["max_kernel"]),
        )
        maps = self._maps()
        plan.check_border(one_pass="large" not in maps, exact="exact" in maps)
        return plan

    def _maps(self) -> set[str]:
        """The maps the current kernel, pass count and view need."""
        if self.values["kernel"] == "exact":
            maps = {"exact"}
        else:
            maps = {"small"} if self.values["one_pass"] else {"blended"}
        if self.values["view"] != "reflector":
            maps.add(self.values["view"])
        if "blended" in maps:
            maps |= {"small", "large"}
        return maps

    def _result_name(self) -> str:
        if self.values["kernel"] == "exact":
            return "exact"
        return "small" if self.values["one_pass"] else "blended"

    def render(self, frame: FrameInputs) -> None:
        plan = self.plan()
        view = self.values["view"]
        maps = self._maps()
        static = frame.scene.static_environment(frame.timer)
        source_key = (id(frame.scene), static.revision, plan.size, plan.border)
        if source_key != self._source_key:
            with frame.timer.measure("hwconv.source"):
                self.convolution.set_source(static.cube, plan.size, plan.border)
            self._source_key, self._filter_key = source_key, None
        filter_key = (source_key, plan, tuple(sorted(maps)))
        if filter_key != self._filter_key or self.values["refilter_every_frame"]:
            self.convolution.filter(plan, maps, frame.timer)
            self._filter_key = filter_key
            self.refilters += 1
        self._result = self.convolution.maps[self._result_name()]
        frame.target.use()
        if view == "reflector":
            self._draw_reflectors(frame, plan)
        else:
            self._draw_map(frame, self.convolution.maps[view])

    def _draw_reflectors(self, frame: FrameInputs, plan: FilterPlan) -> None:
        """Steps 13–14: the reflectors with the prefiltered map and Miller's diffuse map, eq. 2."""
        program = self.programs.get("hwconv/hwconv.glsl")
        self._result.use(front=0, back=1)
        self._diffuse.update(frame, "hwconv").use(location=2)
        set_uniform(program, "u_front", 0)
        set_uniform(program, "u_back", 1)
        set_uniform(program, "u_diffuse_map", 2)
        set_uniform(program, "u_size", float(plan.face_size))
        set_uniform(program, "u_border", float(plan.border))
        set_uniform(program, "u_camera_position", frame.camera_position)
        set_uniform(program, "u_fresnel", tuple(self.values["fresnel"]))
        set_uniform(program, "u_kd", tuple(self.values["kd"]))
        with frame.timer.measure("hwconv"):
            frame.draw_reflectors(program)

    def _draw_map(self, frame: FrameInputs, maps: FaceMaps) -> None:
        """One map as the frame: front face left, back face right (shaders/hwconv/view.glsl)."""
        program = self.programs.get("hwconv/view.glsl")
        maps.use(front=0, back=1)
        set_uniform(program, "u_front", 0)
        set_uniform(program, "u_back", 1)
        with frame.timer.measure("hwconv"):
            self.ctx.disable(moderngl.DEPTH_TEST)
            self._quad.draw(program)
            self.ctx.enable(moderngl.DEPTH_TEST)

    def report_extras(self, session, out_dir: Path) -> list[ReportExtra]:
        """compare's section: the accuracy against the brute force at the compared N.

        render/hwconv_accuracy.run_accuracy with this method's map values at
        :data:`REPORT_DIRECTIONS` directions: RMS and max relative error of the
        2-pass, 1-pass and exact modes, and ``hwconv.accuracy.error_N<N>.png`` in
        ``out_dir`` (write_error_images, scale 1). The values are restored after.
        A scene with local objects gets a note instead (the brute force sees only
        the environment).
        """
        from envstudio.methods.hwconv.accuracy import MODES, run_accuracy, write_error_images

        title = "accuracy against the brute-force Phong prefilter"
        exponent = float(self.values["phong_exponent"])
        if session.scene.local_objects():
            return [
                ReportExtra(
                    title,
                    f"not measured: scene {session.scene.name} has local objects and the "
                    "brute force filters the environment alone",
                )
            ]
        saved = self.values.as_dict()
        errors: dict = {}
        try:
            report = run_accuracy(
                session, [exponent], REPORT_DIRECTIONS, progress=False, errors=errors
            )
        finally:
            self.values.update(saved)
        images = write_error_images(
            report, errors, Path(out_dir) / "hwconv.accuracy.json", scale=1.0, face=REPORT_FACE
        )
        row = report["rows"][0]
        m = report["map"]
        labels = {"two_pass": "2-pass (two maps)", "one_pass": "1-pass", "exact": "exact"}
        text = (
            f"N = {exponent:g}, {report['environment']} ({report['source']}), map "
            f"{m['size']} + 2·{m['border']} from a {m['cube']}² cube, ε = {m['epsilon']:g}, "
            f"maximum kernel {m['max_kernel']}, {report['directions']} directions over the "
            "sphere: relative error per RGB channel (d of the max: 0 the face's centre, 1 the "
            f"rim); brute force {row['brute_s']:.1f} s"
        )
        return [
            ReportExtra(
                title,
                text,
                columns=["mode", "RMS", "max", "d of max", "map texels read"],
                rows=[
                    [
                        labels[mode],
                        f"{row[mode]['rms']:.2%}",
                        f"{row[mode]['max']:.1%}",
                        f"{row[mode]['max_at_d']:.2f}",
                        str(row[mode]["map_texels"]),
                    ]
                    for mode in MODES
                ],
                data=report,
                images=[
                    (
                        path.name,
                        f"N = {exponent:g}: relative error (magma over 0–100 %, saturating "
                        "above), rows 2-pass, 1-pass, exact; front | back face",
                    )
                    for path in images
                ],
            )
        ]

    def release(self) -> None:
        """Free the maps and vertex arrays; safe to call twice."""
        self.convolution.release()
        self._diffuse.release()
        self._quad.release()
        self._result = None
        self._source_key = self._filter_key = None
