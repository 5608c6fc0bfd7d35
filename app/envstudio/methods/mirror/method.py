"""Method ``mirror``: Blinn–Newell mirror reflection with seed 000 eq. 8 and Schlick Fresnel."""

from __future__ import annotations

from envstudio.gpu.uniforms import set_uniform
from envstudio.plugin import EQ8_PARAMETERS, FrameInputs, Method, set_eq8_uniforms


class MirrorMethod(Method):
    """Perfect mirror from the environment cube map, blended with a diffuse term by Fresnel.

    L_o = (1 − F) · k_d · L_blur(n) + F · L_env(r), with Schlick F(r·n) of f_λ
    (seed 000 eq. 8, section 5.2) and L_blur the cube map's 2×2-per-face mip
    level along the normal, a stand-in for irradiance/π without SH. Both read the
    scene's static environment (GpuScene.static_environment): the local objects
    drawn over the far field as seen from the reflectors' centre (seed 003
    Figure 1c), so the teapot in the room reflects the room.
    """

    name = "mirror"
    paper = "Blinn, Newell 1976 (reflection mapping)"
    title = "Mirror (Blinn–Newell)"
    summary = (
        "Mirror reflection from the cube map, Schlick Fresnel blend with a crude diffuse term."
    )
    parameters = EQ8_PARAMETERS

    def render(self, frame: FrameInputs) -> None:
        environment = frame.scene.static_environment(frame.timer)
        frame.target.use()  # a capture may have bound its own framebuffer
        program = self.programs.get("mirror/mirror.glsl")
        environment.cube.use(location=0)
        set_uniform(program, "u_environment", 0)
        set_eq8_uniforms(program, frame, self.values)
        with frame.timer.measure("mirror"):
            for gpu_node in frame.scene.reflectors():
                set_uniform(program, "u_view", frame.view)
                set_uniform(program, "u_projection", frame.projection)
                set_uniform(program, "u_model", gpu_node.model)
                set_uniform(program, "u_normal_matrix", gpu_node.normal)
                gpu_node.mesh.render(program)
