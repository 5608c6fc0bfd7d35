"""The hardware's screen-space LOD of kautz's glossy lookup over the reflector (issue #13).

Under ``lod_mode=bias`` the lookup ``texture(cube, r, b)`` reads level b plus the LOD that
the hardware derives from the screen-space derivatives of r. This script draws the scene's
reflectors once with a probe shader that writes ``textureQueryLod(cube, r).y`` (that LOD,
before the bias and the clamp) and the footprint that kautz.glsl's ``LOD_LEVEL`` branch
estimates, and prints their percentiles over the reflector's pixels. Usage (from the
checkout root, seconds on llvmpipe; OpenGL 4.0 for textureQueryLod):

    python studies/kautz-border-and-sun/screen_lod.py [SCENE] [WxH]

SCENE is a shipped scene's name or a scene file (default ``studio``), WxH the image size
(default 256x256) at the scene's camera and the default 256² cube.
"""

from __future__ import annotations

import argparse

import numpy as np

from envstudio.engine.method import Method
from envstudio.engine.session import RenderSession
from envstudio.gpu.programs import read_shader
from envstudio.gpu.shader_source import preprocess
from envstudio.gpu.uniforms import set_uniform
from envstudio.io.scene_file import load_scene
from envstudio.shading.gpu_scene import FrameInputs

PROBE_NAME = "screen_lod_probe.glsl"
PROBE = """#version 400 core
uniform vec3 u_camera_position;
#if defined VERTEX_SHADER
#include "common/mesh_world.glsl"
uniform mat4 u_view;
uniform mat4 u_projection;
void main() { gl_Position = u_projection * u_view * mesh_world(); }
#elif defined FRAGMENT_SHADER
uniform samplerCube u_environment;
in vec3 v_world_position;
in vec3 v_world_normal;
out vec4 f_color;
void main() {
    vec3 n = normalize(v_world_normal);
    vec3 v = normalize(u_camera_position - v_world_position);
    if (dot(n, v) < 0.0) {
        n = -n;
    }
    vec3 r = reflect(-v, n);
    vec3 rn = normalize(r);  // as kautz.glsl's LOD_LEVEL branch
    float turn = max(length(dFdx(rn)), length(dFdy(rn)));
    float footprint = log2(max(turn * float(textureSize(u_environment, 0).x) * 0.5, 1e-6));
    f_color = vec4(textureQueryLod(u_environment, r).y, footprint, 1.0, 1.0);
}
#endif
"""
PERCENTILES = (10, 25, 50, 75, 90)


def _read(name: str) -> str:
    return PROBE if name == PROBE_NAME else read_shader(name)


class LodProbe(Method):
    """Writes (hardware LOD, estimated footprint, 1) for every reflector pixel."""

    name, title, summary = "screen_lod_probe", "LOD probe", "textureQueryLod over the reflector"
    parameters = ()

    def render(self, frame: FrameInputs) -> None:
        stages = ("VERTEX_SHADER", "FRAGMENT_SHADER")
        vertex, fragment = (preprocess(PROBE_NAME, s, _read, {})[0] for s in stages)
        program = self.ctx.program(vertex_shader=vertex, fragment_shader=fragment)
        frame.target.use()
        frame.scene.static_environment(frame.timer).cube.use(location=0)
        set_uniform(program, "u_environment", 0)
        set_uniform(program, "u_camera_position", frame.camera_position)
        set_uniform(program, "u_view", frame.view)
        set_uniform(program, "u_projection", frame.projection)
        for node in frame.scene.reflectors():
            set_uniform(program, "u_model", node.model)
            set_uniform(program, "u_normal_matrix", node.normal)
            node.mesh.render(program)
        program.release()


def screen_lod(scene: str, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, int]:
    """The hardware LOD and kautz.glsl's footprint estimate at every reflector pixel.

    Parameters
    ----------
    scene
        Shipped scene name or scene file.
    size
        Image width and height, pixels.

    Returns
    -------
    tuple
        (hardware LOD, estimated footprint), each (pixels,) float32 in levels of the
        cube's mip chain, and the cube's face size.
    """
    session = RenderSession(load_scene(scene))
    try:
        session.renderer.display["background"] = False
        session.render_offscreen(LodProbe(session.ctx, session.programs), size)
        image = session.read_hdr()
        mask = image[..., 2] > 0.5
        return image[..., 0][mask], image[..., 1][mask], session.gpu_scene.cube_size
    finally:
        session.release()


def main() -> None:
    """Print the percentiles of both LODs over the reflector."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default="studio")
    parser.add_argument("size", nargs="?", default="256x256")
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x"))
    hardware, estimate, cube = screen_lod(args.scene, size)
    print(f"{args.scene} at {size[0]}x{size[1]}, {cube}² cube, {hardware.size} reflector pixels")
    print("| LOD | " + " | ".join(f"{p}th" for p in PERCENTILES) + " | mean |")
    print("|:--|" + "--:|" * (len(PERCENTILES) + 1))
    for label, values in (
        ("hardware (textureQueryLod)", hardware),
        ("LOD_LEVEL estimate", estimate),
    ):
        cells = " | ".join(f"{v:.2f}" for v in np.percentile(values, PERCENTILES))
        print(f"| {label} | {cells} | {values.mean():.2f} |")


if __name__ == "__main__":
    main()
