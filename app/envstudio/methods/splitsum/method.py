"""Method ``splitsum``: prefiltered GGX radiance times the DFG table (Karis 2013).

The split-sum approximation of the SIGGRAPH 2013 course "Real Shading in Unreal
Engine 4" (Karis), as Filament, three.js and glTF viewers ship it, for the
reference's ``model=microfacet`` material (GGX D, height-correlated Smith G2,
Schlick F of f0 = ``fresnel``; diffuse k_d/π (1 − F(n·v)) E(n)):

    L_o = k_d (1 − F(n·v)) E(n)/π + L_pre(r, α) · (f0 A(n·v, α) + B(n·v, α)) · c,

- L_pre: the environment prefiltered by the GGX lobe with **N = V = R** (the
  lobe's shape does not depend on the view: no stretching at grazing angles, the
  approximation's main error). The assumption is made in
  prefilter.chain_gpu.ggx_lobe_samples, which builds each level on the GPU by
  importance sampling with Křivánek and Colbert's filtered importance sampling
  (GPU Gems 3 ch. 20, EGSR 2008) from the static environment's mip chain.
- A, B: the DFG table (dfg.py), computed once by importance sampling, cached.
- c = 1 + f0 (1/(A + B) − 1): Fdez-Agüera's multiple-scattering energy compensation
  (JCGT 8(1), 2019) as Filament writes it, with ``multiscatter`` (on by default);
  off, c = 1, the single-scattering model the reference renders.
- E(n): SH irradiance with cap lights (shading/sh_irradiance.py), sun-robust by default.

Roughness ↔ level: Filament's mapping (prefilter.roughness, shared with ``envstudio
prefilter --chain --kernel ggx``; cmgen: "map the lod to a linear_roughness,
here we're using ^2"). Of K = log2(n) + 1 levels (n the chain's face edge),
level k holds α_k = (k/(K − 1))², so lod = (K − 1)·√α: linear in the perceptual
roughness √α, which spreads the levels evenly over what the eye sees as
glossiness, and ends at level K − 1 with α = 1, the widest lobe. Level k ≥ 1 has
faces of n/2^k texels but at least 8² (:data:`MIN_LEVEL_EDGE`: a 2² or 1² face does not
hold a wide lobe, issue 30), so the count K, not the sizes, follows the mip chain. Level 0 (α = 0)
is the environment cube itself, read as ``mirror`` reads it (hardware trilinear
with the screen-space LOD): α → 0 is the mirror. A material's α between two
levels blends them (what ``textureLod`` would do on one chain; α is one value per
draw here, so the two levels are two textures, and OpenGL 3.3 suffices).

``lobe_samples`` > 0 replaces L_pre and A, B by per-pixel importance sampling of the
same GGX lobe in the shader (the "no prefiltering" limit: the true view-dependent
lobe, FIS from the environment's mip chain), with the same compensation c.
"""

from __future__ import annotations

import math
import time

import moderngl
import numpy as np

from envstudio.methods.splitsum.dfg import load_dfg_table
from envstudio.plugin import (
    EQ8_PARAMETERS,
    FrameInputs,
    Method,
    Parameter,
    ShIrradiance,
    StaticEnvironment,
    set_eq8_uniforms,
    set_uniform,
    sh_parameters,
)
from envstudio.prefilter import roughness
from envstudio.prefilter.chain_gpu import gpu_filtered_cube, level_samples
from envstudio.prefilter.roughness import level_of

#: The least α: below it the GGX lobe is a mirror to float precision.
MIN_ALPHA = 1e-6
#: The least face edge of a level. The mip-chain sizes n/2^k leave the widest lobes 2² and
#: 1² faces, whose bilinear (seamless) lookups were 13 % off the lobe they hold on studio.exr
#: (α ≥ 0.73 of a 128² chain, issue 30); at 8² they are within 2 % of it, as the larger levels.
MIN_LEVEL_EDGE = 8


def level_alphas(size: int) -> list[float]:
    """α_k of the K = log2(n) + 1 levels of an n² chain (prefilter.roughness.level_alphas)."""
    return roughness.level_alphas(int(math.log2(size)) + 1)


def level_edge(size: int, k: int) -> int:
    """Face edge of level k ≥ 1 of an n² chain: n/2^k, at least :data:`MIN_LEVEL_EDGE` (or n)."""
    return max(min(MIN_LEVEL_EDGE, size), size >> k)


class SplitSumMethod(Method):
    """Karis's split sum: GGX-prefiltered cube levels, the DFG table and SH diffuse."""

    name = "splitsum"
    paper = "Karis 2013 (split sum, Unreal Engine 4)"
    title = "Split sum (prefiltered GGX + DFG)"
    summary = (
        "GGX radiance prefiltered per roughness level (N = V = R) times the DFG table's "
        "scale and bias of F0, multiple-scattering compensation, SH diffuse."
    )
    reflectance = "microfacet"
    parameters = (
        Parameter(
            "roughness",
            "float",
            0.2,
            MIN_ALPHA,
            1.0,
            "α",
            "GGX roughness α in (0, 1] (not the perceptual √α); the level is (K − 1)·√α.",
            log=True,
        ),
        *EQ8_PARAMETERS,
        Parameter(
            "multiscatter",
            "bool",
            True,
            help="Fdez-Agüera 2019 energy compensation 1 + f0 (1/(A + B) − 1); off: single "
            "scattering, the reference's model.",
        ),
        Parameter(
            "lobe_samples",
            "int",
            0,
            0,
            1024,
            "spp",
            "0: the split sum; N > 0: N importance samples of the GGX lobe per pixel at the "
            "same α (no prefiltering, no N = V = R).",
            rebuild=True,
        ),
        Parameter(
            "chain_size",
            "choice",
            "128",
            choices=("32", "64", "128", "256"),
            help="Face edge n of the prefiltered chain (at most the environment cube's); "
            "K = log2(n) + 1 levels.",
        ),
        Parameter(
            "chain_samples",
            "int",
            256,
            16,
            4096,
            "spp",
            "GGX lattice points per texel of level 1, doubling per level.",
            log=True,
        ),
        *sh_parameters("49", 32),
    )

    def __init__(self, ctx: moderngl.Context, programs):
        super().__init__(ctx, programs)
        self._irradiance: ShIrradiance | None = ShIrradiance(ctx, programs)
        self._levels: list[moderngl.TextureCube] = []
        self._chain_key: tuple | None = None
        self._dfg: moderngl.Texture | None = None
        #: Wall time of the last chain build, s (None before the first).
        self.chain_seconds: float | None = None

    def chain_alphas(self, static: StaticEnvironment) -> list[float]:
        """α of each level of the chain this method builds for ``static`` (level 0: 0)."""
        return level_alphas(min(int(self.values["chain_size"]), static.cube.size[0]))

    def render(self, frame: FrameInputs) -> None:
        static = frame.scene.static_environment(frame.timer)
        self._irradiance.update_static(frame, self.values, "splitsum")
        sampled = int(self.values["lobe_samples"]) > 0
        if not sampled:
            self._update_chain(frame, static)
        if self._dfg is None:
            self._dfg = self._upload_dfg()
        frame.target.use()  # the prefilter bound its own framebuffers
        defines = {**ShIrradiance.defines(self.values), "SAMPLED": int(sampled)}
        program = self.programs.get("splitsum/splitsum.glsl", defines)
        self._irradiance.bind(program)
        alpha = float(self.values["roughness"])
        if sampled:
            static.cube.use(location=0)
            n = static.cube.size[0]
            set_uniform(program, "u_environment", 0)
            set_uniform(program, "u_samples", int(self.values["lobe_samples"]))
            set_uniform(program, "u_source_max", float(n.bit_length() - 1))
            set_uniform(program, "u_texel_log2", math.log2(2.0 / n))
        else:
            k, t = level_of(alpha, len(self._levels) + 1)
            (static.cube if k == 0 else self._levels[k - 1]).use(location=0)
            self._levels[k].use(location=1)
            set_uniform(program, "u_level_a", 0)
            set_uniform(program, "u_level_b", 1)
            set_uniform(program, "u_level_mix", t)
        self._dfg.use(location=2)
        set_uniform(program, "u_dfg", 2)
        set_uniform(program, "u_roughness", alpha)
        set_uniform(program, "u_multiscatter", bool(self.values["multiscatter"]))
        set_eq8_uniforms(program, frame, self.values)
        with frame.timer.measure("splitsum"):
            frame.draw_reflectors(program)

    def _update_chain(self, frame: FrameInputs, static: StaticEnvironment) -> None:
        """Filter levels 1 … K − 1 when the environment or a chain setting changed."""
        size = min(int(self.values["chain_size"]), static.cube.size[0])
        samples = int(self.values["chain_samples"])
        key = (id(frame.scene), static.revision, size, samples)
        if key == self._chain_key:
            return
        self._release_levels()
        start = time.perf_counter()
        with frame.timer.measure("splitsum.prefilter"):
            for k, alpha in enumerate(level_alphas(size)[1:], start=1):
                m = level_edge(size, k)
                count = level_samples(samples, k - 1)
                faces = gpu_filtered_cube(self.ctx, self.programs, static.cube, m, alpha, count)
                cube = self.ctx.texture_cube((m, m), 3, dtype="f4")
                for face in range(6):
                    cube.write(face, np.ascontiguousarray(faces[face]).tobytes())
                cube.filter = (moderngl.LINEAR, moderngl.LINEAR)
                self._levels.append(cube)
        self.chain_seconds = time.perf_counter() - start
        self._chain_key = key

    def _upload_dfg(self) -> moderngl.Texture:
        """The DFG table as an RG32F texture, bilinear, clamped (rows √α, columns n·v)."""
        table = load_dfg_table()
        tex = self.ctx.texture(table.shape[1::-1], 2, table.tobytes(), dtype="f4")
        tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
        tex.repeat_x = tex.repeat_y = False
        return tex

    def bench_notes(self) -> dict:
        """The chain's build time (wall clock, read-back included) and its levels."""
        return {
            "chain_build_s": self.chain_seconds,
            "chain_levels": len(self._levels) + 1,
        }

    def _release_levels(self) -> None:
        for cube in self._levels:
            cube.release()
        self._levels = []
        self._chain_key = None

    def release(self) -> None:
        """Free the chain, the DFG texture and the SH block; safe to call twice."""
        self._release_levels()
        if self._dfg is not None:
            self._dfg.release()
        self._dfg = None
        if self._irradiance is not None:
            self._irradiance.release()
        self._irradiance = None
