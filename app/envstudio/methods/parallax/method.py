"""Method ``parallax``: parallax-corrected cube maps (Lagarde and Zanuttini 2012).

Lagarde and Zanuttini, "Local image-based lighting with parallax-corrected
cubemaps", SIGGRAPH 2012 talk: the engines' answer to the static EM's missing
parallax (seed 003 §1, Figure 1c). One cube map is captured at a probe point; a
simple proxy volume (a box or a sphere) stands for the geometry it shows. Each
reflection ray p + t·r is intersected with the proxy, and the cube is read towards
the hit x − c (c the probe) instead of along r, so a wall is found where it stands
rather than where it would be seen from the probe (shaders/parallax/parallax.glsl).

- **Probe and proxy.** The scene's ``[proxy]`` (io/scene_file.py, scene/proxy.py): an
  axis-aligned box or a sphere, and optionally ``probe``. The cube is the scene's
  static environment (GpuScene.static_environment), captured at the reflectors'
  centre; a declared probe elsewhere gets its own capture there, the same one-pass
  cube capture (envmap.dynamic_cube), once per scene change.
- **Glossy** (``glossy_chain=phong``, the default). A Phong-prefiltered mip chain of
  the probe's cube, built on the GPU by filtered importance sampling
  (prefilter.chain_gpu.gpu_phong_cube_chain, the pass ``splitsum`` uses for GGX) once
  per probe cube, at the cube's face edge n: level k holds N_k = (n / 2^(k+1))², a lobe
  one of its texels wide (chain_gpu.texel_exponents), so the lookup reads the
  fractional level log2(n) − 1 − ½ log2 N' (trilinear: log-linear in N between two
  levels). Where that lobe is no wider than the pixel's footprint, the lookup is the
  hardware's own on the probe's cube (so a mirror-like N with the proxy at infinity is
  exactly ``mirror``).
  ``glossy_chain=box`` reads the probe cube's box-filtered mips instead, at the level
  whose blur looks like the lobe by the fitted b ↔ N mapping of prefilter/glossiness.py
  (``kautz`` with ``lod_mode=level``): nothing to build, about 0.12 levels RMS off.
- **Distance-based lobe correction** (Lagarde and Zanuttini's, as their course
  notes with de Rousiers restate it, "Moving Frostbite to PBR", 2014): the
  chain was filtered about the probe, but the lobe opens at p. A lobe of angle θ
  about r covers a patch |x − p|·θ wide on the proxy, which the probe sees under
  θ·|x − p| / |x − c|; a Phong lobe is about N^−½ wide, so the lookup takes
  N' = N·(|x − c| / |x − p|)². Off with ``distance_correction=false``.
- **Diffuse.** SH irradiance E(n) of the static environment (shading/sh_irradiance.py),
  combined with the glossy term by seed 000 eq. 8 with Schlick's F, as ``mirror``.

Without a proxy, a scene whose only light is the environment at infinity needs no
correction: the lookup is along r (the status line says so). A scene with local
objects and no proxy is refused with one line saying how to declare one.
"""

from __future__ import annotations

import time

import moderngl
import numpy as np

from envstudio.envmap.dynamic_cube import DynamicCube
from envstudio.plugin import (
    EQ8_PARAMETERS,
    FrameInputs,
    GpuScene,
    Method,
    Parameter,
    ShIrradiance,
    UserError,
    set_eq8_uniforms,
    set_uniform,
    sh_parameters,
)
from envstudio.prefilter.chain_gpu import gpu_phong_cube_chain
from envstudio.prefilter.glossiness import load_model
from envstudio.scene.proxy import BoxProxy, Proxy, SphereProxy

#: How a scene declares a proxy, for the one line that asks for one.
DECLARE = (
    'declare one in the scene file as [proxy] shape = "box", min = [x, y, z], '
    'max = [x, y, z] (or shape = "sphere", centre = [x, y, z], radius = R), '
    "optionally probe = [x, y, z]"
)


class ParallaxMethod(Method):
    """A cube map captured at a probe, read towards the reflection ray's hit on a proxy."""

    name = "parallax"
    paper = "Lagarde, Zanuttini 2012 (SIGGRAPH talk)"
    title = "Parallax-corrected cube map (Lagarde–Zanuttini 2012)"
    summary = (
        "The static cube captured at a probe, each reflection ray intersected with the "
        "scene's proxy box or sphere before the lookup; glossy from its Phong-prefiltered "
        "mip chain with the distance-based lobe correction; SH diffuse, Schlick Fresnel."
    )
    parameters = (
        Parameter(
            "phong_exponent",
            "float",
            100.0,
            1.0,
            1.0e6,
            "N",
            "Phong exponent of the glossy lobe: the chain level whose lobe it is (a large N "
            "is the mirror).",
            log=True,
        ),
        Parameter(
            "glossy_chain",
            "choice",
            "phong",
            choices=("phong", "box"),
            rebuild=True,
            help="phong: the probe cube's Phong-prefiltered chain, one exponent per level "
            "(built on the GPU once per probe cube); box: its box-filtered mips at the level "
            "the fitted b ↔ N mapping gives.",
        ),
        Parameter(
            "parallax",
            "bool",
            True,
            rebuild=True,
            help="Intersect each reflection ray with the proxy before the lookup (off: the "
            "probe's cube read along r, as without correction).",
        ),
        Parameter(
            "distance_correction",
            "bool",
            True,
            rebuild=True,
            help="Scale the lobe by the distance from the point to the proxy against the "
            "probe's: N' = N (|x − c| / |x − p|)².",
        ),
        *EQ8_PARAMETERS,
        *sh_parameters("49", 32),
    )

    def __init__(self, ctx: moderngl.Context, programs):
        super().__init__(ctx, programs)
        self._irradiance: ShIrradiance | None = ShIrradiance(ctx, programs)
        self._probe_cube: DynamicCube | None = None
        self._probe_key: tuple | None = None
        self._chain: moderngl.TextureCube | None = None
        self._chain_key: tuple | None = None
        #: Wall time of the last Phong chain build, s (None before the first).
        self.chain_seconds: float | None = None
        self._note = ""

    # -- the scene's proxy and probe -----------------------------------------------------------

    def prepare(self, scene: GpuScene) -> None:
        """Check the scene's proxy and probe; raises UserError (one line) when unusable."""
        self._proxy_and_probe(scene)

    def _proxy_and_probe(self, scene: GpuScene) -> tuple[Proxy | None, np.ndarray]:
        """The scene's proxy (None: none, rays along r) and the probe c, (3,) float64."""
        proxy = scene.scene.proxy
        centre = np.asarray(scene.reflector_centre(), dtype=np.float64)
        if proxy is None:
            if scene.local_objects():
                raise UserError(
                    f"method parallax: scene {scene.scene.name} has local objects but no "
                    f"proxy volume; {DECLARE}"
                )
            self._note = (
                f"no proxy in scene {scene.scene.name}: the environment alone is at infinity, "
                "read along r"
            )
            return None, centre
        probe = centre if proxy.probe is None else np.asarray(proxy.probe, dtype=np.float64)
        if not proxy.contains(probe):
            which = "the reflectors' centre (the probe)" if proxy.probe is None else "its probe"
            raise UserError(
                f"method parallax: the proxy {proxy.describe()} of scene {scene.scene.name} "
                f"does not contain {which} [{', '.join(f'{v:g}' for v in probe)}]; expected "
                "the probe inside the proxy"
            )
        self._note = f"proxy {proxy.describe()}, probe [{', '.join(f'{v:g}' for v in probe)}]"
        return proxy, probe

    def status_line(self) -> str:
        """The proxy and probe in use, or why there is none."""
        return self._note

    # -- rendering ---------------------------------------------------------------------------

    def render(self, frame: FrameInputs) -> None:
        proxy, probe = self._proxy_and_probe(frame.scene)
        cube, source_key = self._probe_environment(frame, probe)
        phong = self.values["glossy_chain"] == "phong"
        if phong:
            self._update_chain(frame, cube, source_key)
        self._irradiance.update_static(frame, self.values, "parallax")
        frame.target.use()  # a capture or the chain's passes bound their own framebuffers
        corrected = proxy is not None and self.values["parallax"]
        defines = {
            "PROXY": {"box": 1, "sphere": 2}[proxy.shape] if corrected else 0,
            "DISTANCE_CORRECTION": int(bool(self.values["distance_correction"])),
            "PHONG_CHAIN": int(phong),
            **ShIrradiance.defines(self.values),
        }
        program = self.programs.get("parallax/parallax.glsl", defines)
        self._irradiance.bind(program)
        cube.use(location=0)
        set_uniform(program, "u_environment", 0)
        if phong:
            self._chain.use(location=1)
            set_uniform(program, "u_chain", 1)
        else:
            fit = load_model()
            set_uniform(program, "u_fit", (fit.a, fit.c, fit.d))
        if isinstance(proxy, BoxProxy):
            set_uniform(program, "u_box_min", tuple(float(v) for v in proxy.minimum))
            set_uniform(program, "u_box_max", tuple(float(v) for v in proxy.maximum))
        elif isinstance(proxy, SphereProxy):
            set_uniform(program, "u_sphere_centre", tuple(float(v) for v in proxy.centre))
            set_uniform(program, "u_sphere_radius", float(proxy.radius))
        set_uniform(program, "u_probe", tuple(float(v) for v in probe))
        set_uniform(program, "u_exponent", float(self.values["phong_exponent"]))
        set_uniform(program, "u_cube_size", float(cube.size[0]))
        set_eq8_uniforms(program, frame, self.values)
        with frame.timer.measure("parallax"):
            frame.draw_reflectors(program)

    def _probe_environment(
        self, frame: FrameInputs, probe: np.ndarray
    ) -> tuple[moderngl.TextureCube, tuple]:
        """The cube seen from the probe, and a key that changes whenever its content does.

        The static environment is captured at the reflectors' centre; a probe elsewhere,
        in a scene with local objects, gets its own capture (once per scene change).
        """
        scene = frame.scene
        static = scene.static_environment(frame.timer)
        key = (id(scene), static.revision, probe.tobytes())
        if not static.captured or np.array_equal(probe, scene.reflector_centre()):
            self._release_probe()
            return static.cube, key
        if self._probe_cube is None or self._probe_cube.size != scene.cube_size:
            self._release_probe()
            self._probe_cube = DynamicCube(self.ctx, self.programs, scene.cube_size)
        if key != self._probe_key:
            with frame.timer.measure("parallax.capture"):
                self._probe_cube.capture(
                    scene.cube, scene.sh9, scene.local_capture_objects(), probe
                )
                self._probe_cube.build_mipmaps(cross_face=False)
            self._probe_key = key
        return self._probe_cube.cube, key

    def _update_chain(self, frame: FrameInputs, cube: moderngl.TextureCube, key: tuple) -> None:
        """Build the Phong chain of the probe's cube (its face edge) when the cube changed."""
        key = (*key, cube.size[0])
        if key == self._chain_key:
            return
        self._release_chain()
        start = time.perf_counter()
        with frame.timer.measure("parallax.prefilter"):
            self._chain = gpu_phong_cube_chain(self.ctx, self.programs, cube, cube.size[0])
        self.chain_seconds = time.perf_counter() - start
        self._chain_key = key

    def bench_notes(self) -> dict:
        """The Phong chain's build time (wall clock, read-back included) and its levels."""
        if self._chain is None:
            return {}
        return {
            "chain_build_s": self.chain_seconds,
            "chain_levels": self._chain.size[0].bit_length(),
        }

    # -- resources ---------------------------------------------------------------------------

    def _release_probe(self) -> None:
        if self._probe_cube is not None:
            self._probe_cube.release()
        self._probe_cube = None
        self._probe_key = None

    def _release_chain(self) -> None:
        if self._chain is not None:
            self._chain.release()
        self._chain = None
        self._chain_key = None

    def release(self) -> None:
        """Free the SH block, the probe's capture and its chain; safe to call twice."""
        if self._irradiance is not None:
            self._irradiance.release()
        self._irradiance = None
        self._release_probe()
        self._release_chain()
