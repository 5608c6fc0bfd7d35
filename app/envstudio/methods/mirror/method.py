"""Method ``mirror``: Blinn–Newell mirror reflection with seed 000 eq. 8 and Schlick Fresnel."""

from __future__ import annotations

import moderngl

from envstudio.plugin import (
    EQ8_PARAMETERS,
    FrameInputs,
    Method,
    ShIrradiance,
    set_eq8_uniforms,
    set_uniform,
    sh_parameters,
)


class MirrorMethod(Method):
    """Perfect mirror from the environment cube map, blended with SH irradiance by Fresnel.

    L_o = (1 − F) · k_d · E(n)/π + F · L_env(r), with Schlick F(r·n) of f_λ
    (seed 000 eq. 8, section 5.2) and E(n) the irradiance ``kautz`` has: SH
    (eq. 12) plus cap lights (shading/sh_irradiance.py), by default 49
    coefficients and 32 lights, within 0.2 % of the exact irradiance on the
    shipped maps. Both read the scene's static environment
    (GpuScene.static_environment): the local objects drawn over the far field as
    seen from the reflectors' centre (seed 003 Figure 1c), so the teapot in the
    room reflects the room.
    """

    name = "mirror"
    paper = "Blinn, Newell 1976 (reflection mapping)"
    title = "Mirror (Blinn–Newell)"
    summary = "Mirror reflection from the cube map, Schlick Fresnel blend with SH irradiance."
    parameters = (*EQ8_PARAMETERS, *sh_parameters("49", 32))

    def __init__(self, ctx: moderngl.Context, programs):
        super().__init__(ctx, programs)
        self._irradiance: ShIrradiance | None = ShIrradiance(ctx, programs)

    def render(self, frame: FrameInputs) -> None:
        environment = frame.scene.static_environment(frame.timer)
        self._irradiance.update_static(frame, self.values, "mirror")
        frame.target.use()  # a capture may have bound its own framebuffer
        program = self.programs.get("mirror/mirror.glsl", ShIrradiance.defines(self.values))
        self._irradiance.bind(program)
        environment.cube.use(location=0)
        set_uniform(program, "u_environment", 0)
        set_eq8_uniforms(program, frame, self.values)
        with frame.timer.measure("mirror"):
            frame.draw_reflectors(program)

    def release(self) -> None:
        """Free the SH block; safe to call twice."""
        if self._irradiance is not None:
            self._irradiance.release()
        self._irradiance = None
