"""Per-frame cube-map capture of the surroundings of a reflector (seed 000 section 5.1).

"From x we need to render the environment six times, i.e. one pass for every face
of the cube map. All we need to do, is to set the field-of-view to 90 degrees and
to rotate the view direction according to every face." :class:`DynamicCube` does
that from the reflector's centre, but in one pass rather than six: the faces of
level 0 lie side by side in a 6n × n strip (face f in columns [f n, (f + 1) n)),
the environment at infinity is drawn over the whole strip by one full-screen
triangle (each pixel looks up its face texel's direction), and every local
object (diffuse, lit by the environment's SH9, as the frame's local pass does)
by one draw of six instances, instance f seen by face camera f and clipped to
its sixth of the strip (shaders/envmap/capture_local.glsl). A compute pass then
copies the strip into the cube's faces (moderngl cannot attach a cube face to a
framebuffer). Six passes cost six clears, six background draws, six draws per
object and twelve copies, each issued from Python; on the H100 they took
0.7–1.0 ms of the dynamic update, past the 1 ms the whole update may take. On a
context older than 4.3 (no compute shaders) the strip goes into the faces
through a pixel buffer instead, still without leaving the GPU, so the static
environment cube of every method (methods.context.GpuScene.static_environment)
can be captured on OpenGL 3.3 too. The mip chain is then the hardware box filter
or the cross-face filter of :mod:`envstudio.envmap.mipmaps`.

Face cameras, from the OpenGL cube-map table (core.cubemap): a face texel at
(a, b) = (2s − 1, 2t − 1) looks along forward + a · right + b · up, so the view
rotation has the rows (right, up, −forward) and a 90° projection puts (a, b) at
normalised device coordinates (a, b); framebuffer row 0 (y = −1) is t = 0, the
face's row 0, so the pixels are copied without a flip::

    face   forward   right     up
    +X     +x        −z        −y
    −X     −x        +z        −y
    +Y     +y        +x        +z
    −Y     −y        +x        −z
    +Z     +z        +x        −y
    −Z     −z        −x        −y
"""

from __future__ import annotations

from collections.abc import Sequence

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.transforms import Mat4, perspective
from envstudio.envmap.mipmaps import build_cross_face_mipmaps, mipmapped_cube
from envstudio.gpu.context import has_compute
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.gpu.mesh import GpuMesh
from envstudio.gpu.programs import ProgramLibrary
from envstudio.gpu.uniforms import set_uniform

__all__ = ["FACE_AXES", "DynamicCube", "LocalObject", "face_view"]

GL_CLIP_DISTANCE0 = 0x3000  # glEnable target of gl_ClipDistance[0]; moderngl has no name for it

#: What the capture draws of a local object: mesh, model matrix (4, 4), normal
#: matrix (3, 3) and diffuse albedo (r, g, b).
LocalObject = tuple[GpuMesh, Mat4, npt.NDArray[np.float32], tuple[float, float, float]]

#: (forward, right, up) world axes of the six face cameras, OpenGL face order.
FACE_AXES = np.array(
    [
        [[1, 0, 0], [0, 0, -1], [0, -1, 0]],
        [[-1, 0, 0], [0, 0, 1], [0, -1, 0]],
        [[0, 1, 0], [1, 0, 0], [0, 0, 1]],
        [[0, -1, 0], [1, 0, 0], [0, 0, -1]],
        [[0, 0, 1], [1, 0, 0], [0, -1, 0]],
        [[0, 0, -1], [-1, 0, 0], [0, -1, 0]],
    ],
    dtype=np.float64,
)


def face_view(face: int, centre: npt.ArrayLike) -> Mat4:
    """World → view matrix of the camera of cube face ``face`` at ``centre``.

    Parameters
    ----------
    face
        0 … 5, OpenGL face order.
    centre
        (3,) float, the capture point in world space.

    Returns
    -------
    (4, 4) float32
        Rotation rows (right, up, −forward) of :data:`FACE_AXES`, then −centre.
    """
    forward, right, up = FACE_AXES[face]
    view = np.eye(4)
    view[:3, :3] = np.stack([right, up, -forward])
    view[:3, 3] = -view[:3, :3] @ np.asarray(centre, dtype=np.float64)
    return view.astype(np.float32)


class DynamicCube:
    """A cube map re-rendered from a point every frame, with its mip chain.

    Parameters
    ----------
    ctx, programs
        Context and its program library (the cross-face chain needs OpenGL 4.3).
    size
        Face edge n in texels of level 0.
    near, far
        Clip distances of the face cameras in scene units.
    compute_copy
        Copy the strip into the faces with a compute pass (OpenGL 4.3) rather than
        through a pixel buffer; None: whenever the context has compute shaders.
    """

    def __init__(
        self,
        ctx: moderngl.Context,
        programs: ProgramLibrary,
        size: int,
        near: float = 0.01,
        far: float = 1000.0,
        compute_copy: bool | None = None,
    ):
        self.ctx = ctx
        self.programs = programs
        self.size = size
        self.compute_copy = has_compute(ctx) if compute_copy is None else compute_copy
        self.projection = perspective(90.0, 1.0, near, far)
        self.cube: moderngl.TextureCube | None = mipmapped_cube(ctx, size)
        self._strip = ctx.texture((6 * size, size), 4, dtype="f4")
        self._depth = ctx.depth_renderbuffer((6 * size, size))
        self._fbo = ctx.framebuffer([self._strip], self._depth)
        self._fullscreen = FullscreenPass(ctx)
        self._centre: tuple[float, ...] | None = None
        self._views = np.zeros((6, 4, 4), dtype=np.float32)  # face_view of each face at _centre

    def capture(
        self,
        environment: moderngl.TextureCube,
        sh9: npt.ArrayLike,
        objects: Sequence[LocalObject],
        centre: npt.ArrayLike,
    ) -> None:
        """Render the six faces of level 0 from ``centre``: background, then local objects.

        Parameters
        ----------
        environment
            The environment at infinity (its level 0 is the background).
        sh9
            (9, 3) float, the environment's SH coefficients that light the local objects.
        objects
            The local objects to draw (never the reflector itself).
        centre
            (3,) float, world-space capture point (the reflector's centre).
        """
        background = self.programs.get("envmap/capture_background.glsl")
        local = self.programs.get("envmap/capture_local.glsl")
        centre_key = tuple(float(c) for c in np.asarray(centre).ravel())
        if centre_key != self._centre:
            self._views = np.stack([face_view(face, centre_key) for face in range(6)])
            self._centre = centre_key
        set_uniform(local, "u_face_views", self._views)
        set_uniform(local, "u_projection", self.projection)
        environment.use(location=0)
        set_uniform(background, "u_environment", 0)
        set_uniform(background, "u_size", self.size)
        set_uniform(local, "u_sh9", np.asarray(sh9, dtype=np.float32))
        with self.ctx.scope(self._fbo, enable_only=moderngl.NOTHING):
            self.ctx.viewport = (0, 0, 6 * self.size, self.size)
            self._fbo.clear(depth=1.0)
            self._fullscreen.draw(background)
            self.ctx.enable(moderngl.DEPTH_TEST)
            self.ctx.enable_direct(GL_CLIP_DISTANCE0)
            self.ctx.enable_direct(GL_CLIP_DISTANCE0 + 1)
            for mesh, model, normal, albedo in objects:
                set_uniform(local, "u_model", model)
                set_uniform(local, "u_normal_matrix", normal)
                set_uniform(local, "u_albedo", tuple(float(c) for c in albedo))
                mesh.render(local, instances=6)
            self.ctx.disable_direct(GL_CLIP_DISTANCE0)
            self.ctx.disable_direct(GL_CLIP_DISTANCE0 + 1)
        if self.compute_copy:
            self._copy_by_compute()
        else:
            self._copy_by_buffer()

    def _copy_by_compute(self) -> None:
        """Strip → level 0 of the faces in one compute pass (shaders/envmap/capture_copy.glsl)."""
        copy = self.programs.compute("envmap/capture_copy.glsl")
        self._strip.use(location=0)
        set_uniform(copy, "u_strip", 0)
        set_uniform(copy, "u_size", self.size)
        self.cube.bind_to_image(0, read=False, write=True, level=0)
        groups = (self.size + 7) // 8
        copy.run(groups, groups, 6)
        self.ctx.memory_barrier(moderngl.ALL_BARRIER_BITS)

    def _copy_by_buffer(self) -> None:
        """Strip → level 0 of the faces through a pixel buffer, face by face (OpenGL 3.3).

        Columns [f n, (f + 1) n) of the strip are read into the buffer and written
        as face f, row for row, as the compute copy does.
        """
        n = self.size
        pixels = self.ctx.buffer(reserve=n * n * 16)
        try:
            for face in range(6):
                self._fbo.read_into(pixels, (face * n, 0, n, n), components=4, dtype="f4")
                self.cube.write(face, pixels)
        finally:
            pixels.release()

    def build_mipmaps(self, cross_face: bool) -> None:
        """Rebuild levels 1 … from level 0: hardware box filter, or the cross-face filter."""
        if cross_face:
            build_cross_face_mipmaps(self.ctx, self.programs, self.cube)
        else:
            self.cube.build_mipmaps()

    def release(self) -> None:
        """Free the cube map, targets and buffers; safe to call twice."""
        for obj in (self._fbo, self._strip, self._depth, self.cube):
            if obj is not None:
                obj.release()
        self._fbo = self._strip = self._depth = self.cube = None
        self._fullscreen.release()
