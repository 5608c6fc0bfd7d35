"""Meshes on the GPU: buffers once, one vertex array per program."""

from __future__ import annotations

import moderngl
import numpy as np

from envstudio.scene.mesh import MeshData


class GpuMesh:
    """Vertex and index buffers of one :class:`MeshData`.

    Vertex layout: ``in_position`` (vec3) and ``in_normal`` (vec3), interleaved.
    Programs that omit an attribute still work (unused attributes are skipped).
    """

    def __init__(self, ctx: moderngl.Context, mesh: MeshData):
        self.ctx = ctx
        self.triangle_count = mesh.triangle_count
        interleaved = np.hstack([mesh.positions, mesh.normals]).astype(np.float32)
        self.vbo = ctx.buffer(interleaved.tobytes())
        self.ibo = ctx.buffer(mesh.indices.astype(np.uint32).tobytes())
        self._vaos: dict[int, moderngl.VertexArray] = {}

    def vao(self, program: moderngl.Program) -> moderngl.VertexArray:
        """The vertex array binding this mesh to ``program`` (built on first use)."""
        vao = self._vaos.get(program.glo)
        if vao is None:
            names = [n for n in ("in_position", "in_normal") if n in program]
            layout = " ".join("3f" if n in names else "12x" for n in ("in_position", "in_normal"))
            vao = self.ctx.vertex_array(
                program, [(self.vbo, layout, *names)], index_buffer=self.ibo, index_element_size=4
            )
            self._vaos[program.glo] = vao
        return vao

    def render(self, program: moderngl.Program, instances: int = 1) -> None:
        """Draw all triangles with ``program`` into the bound framebuffer, ``instances`` times."""
        self.vao(program).render(moderngl.TRIANGLES, instances=instances)

    def release(self) -> None:
        """Free buffers and vertex arrays; safe to call twice."""
        for vao in self._vaos.values():
            vao.release()
        self._vaos.clear()
        for buf in (self.vbo, self.ibo):
            if buf is not None:
                buf.release()
        self.vbo = self.ibo = None
