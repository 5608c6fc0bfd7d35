"""The playback's per-pixel EM lookups rendered by the playback shader itself (issue 18).

Issue 18 asks that the rendering matrix A be built "from the exact texture
coordinates and mip level the playback shader will use: render the lookup
vector and the level per pixel on the GPU". :class:`GlLookups` draws the scene
with shaders/pem/pem.glsl compiled with ``PEM_LOOKUP``: the same texgen, face
selection and ``dFdx``/``dFdy`` level as the playback, written per pixel to five
RGBA32F targets instead of shaded (distant, local, sphere, part, ptm). The result is the
:class:`~envstudio.methods.pem.bake.lookups.PixelLookups` that
:func:`~envstudio.methods.pem.bake.lookups.pixel_lookups` computes on the CPU, so the
bake's A and the playback agree texel for texel on this GL.
"""

from __future__ import annotations

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.transforms import normal_matrix
from envstudio.gpu.context import create_headless_context
from envstudio.gpu.mesh import GpuMesh
from envstudio.gpu.programs import ProgramLibrary
from envstudio.methods.pem.bake.lookups import MODELS, PixelLookups
from envstudio.plugin import set_uniform
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.graph import Scene

__all__ = ["GlLookups"]


class GlLookups:
    """Renders the playback's lookups of a scene's reflector parts.

    Parameters
    ----------
    scene
        The scene (its reflectors are the parts, in order; local objects occlude).
    ctx
        A context; None makes a headless EGL one (owned and released here).
    texgen
        ``fragment`` or ``vertex``: the playback's texgen mode the lookups are for.
    """

    def __init__(self, scene: Scene, ctx: moderngl.Context | None = None, texgen: str = "fragment"):
        from envstudio.gpu.context import create_headless_context
        from envstudio.methods.pem.gpu import texgen_defines

        defines = {"PEM_LOOKUP": 1, **texgen_defines(texgen)}
        self._owns = ctx is None
        self.ctx = ctx or create_headless_context()
        self.programs = ProgramLibrary(self.ctx)
        self.program = self.programs.get("pem/pem.glsl", defines)
        reflectors = scene.reflectors()
        self._nodes = [(n, GpuMesh(self.ctx, n.mesh), i) for i, n in enumerate(reflectors)]
        self._nodes += [(n, GpuMesh(self.ctx, n.mesh), -1) for n in scene.local_objects()]
        self._hull = self.ctx.texture((1, 1), 1, b"\0", dtype="u1")
        self._fbo: moderngl.Framebuffer | None = None

    @staticmethod
    def unavailable() -> str | None:
        """Why no headless GL context can be made here (None when one can)."""
        try:
            create_headless_context().release()
        except Exception as exc:  # ContextError, or a driver's own error
            return str(exc).splitlines()[0]
        return None

    def _target(self, size: int) -> moderngl.Framebuffer:
        if self._fbo is None or self._fbo.size != (size, size):
            self._release_target()
            colours = [self.ctx.texture((size, size), 4, dtype="f4") for _ in range(5)]
            depth = self.ctx.depth_renderbuffer((size, size))
            self._fbo = self.ctx.framebuffer(colours, depth)
        return self._fbo

    def render(
        self,
        camera: OrbitCamera,
        size: int,
        em_size: int,
        box: npt.ArrayLike,
        origins: npt.ArrayLike,
        ellipsoids: npt.ArrayLike,
    ) -> PixelLookups:
        """The lookups of one view (``PixelLookups``, row 0 at the top).

        Parameters
        ----------
        camera
            The view (square image, aspect 1).
        size
            R, pixels per side.
        em_size
            n, level 0's face edge (the scale of the level).
        box
            (2, 3) the distant box's lo and hi corners.
        origins
            (P, 3) EM origin per part.
        ellipsoids
            (P, 2, 3) each part's local ellipsoid: centre, radii.
        """
        if not self._owns:  # the caller's context, current as the caller keeps it
            return self._render(camera, size, em_size, box, origins, ellipsoids)
        with self.ctx:  # ours: made current for these calls, whatever was current before
            return self._render(camera, size, em_size, box, origins, ellipsoids)

    def _render(self, camera, size, em_size, box, origins, ellipsoids) -> PixelLookups:
        fbo = self._target(size)
        fbo.use()
        fbo.clear(-1.0, -1.0, -1.0, -1.0, depth=1.0)
        self.ctx.enable(moderngl.DEPTH_TEST)
        self.ctx.disable(moderngl.BLEND | moderngl.CULL_FACE)
        program = self.program
        box = np.asarray(box, dtype=np.float64)
        origins = np.asarray(origins, dtype=np.float64)
        ellipsoids = np.asarray(ellipsoids, dtype=np.float64)
        set_uniform(program, "u_view", camera.view_matrix())
        set_uniform(program, "u_projection", camera.projection_matrix(1.0))
        set_uniform(program, "u_camera_position", camera.position)
        set_uniform(program, "u_box_lo", box[0])
        set_uniform(program, "u_box_hi", box[1])
        set_uniform(program, "u_em_size", int(em_size))
        self._hull.use(location=0)
        set_uniform(program, "u_hull", 0)
        set_uniform(program, "u_use_hull", False)
        for node, mesh, part in self._nodes:
            k = max(part, 0)
            set_uniform(program, "u_part", part)
            set_uniform(program, "u_em_origin", origins[k])
            set_uniform(program, "u_ellipsoid_centre", ellipsoids[k, 0])
            set_uniform(program, "u_ellipsoid_radii", ellipsoids[k, 1])
            model = node.transform.matrix()
            set_uniform(program, "u_model", model)
            set_uniform(program, "u_normal_matrix", normal_matrix(model))
            mesh.render(program)
        images = [
            np.frombuffer(a.read(), np.float32).reshape(size, size, 4)[::-1]
            for a in fbo.color_attachments
        ]
        part = np.rint(images[3][..., 0]).astype(np.int8)
        on = part >= 0
        part[~on] = -1
        lookups = PixelLookups(
            size=size,
            em_size=int(em_size),
            part=part,
            triangle=np.where(on, np.rint(images[3][..., 2]), -1).astype(np.int32),
        )
        for model, image in zip(MODELS, [*images[:3], images[4]], strict=True):
            lookups.face[model] = np.where(on, np.rint(image[..., 0]), -1).astype(np.int8)
            lookups.st[model] = np.where(on[..., None], image[..., 1:3], 0.0).astype(np.float32)
            lookups.lod[model] = np.where(on, image[..., 3], 0.0).astype(np.float32)
        return lookups

    def _release_target(self) -> None:
        if self._fbo is not None:
            for attachment in self._fbo.color_attachments:
                attachment.release()
            self._fbo.depth_attachment.release()
            self._fbo.release()
            self._fbo = None

    def release(self) -> None:
        """Free the GPU resources (and the context if made here); safe to call twice."""
        self._release_target()
        for _, mesh, _ in self._nodes:
            mesh.release()
        self._nodes = []
        if self._hull is not None:
            self._hull.release()
            self._hull = None
        if self._owns and self.ctx is not None:
            self.ctx.release()
            self.ctx = None
