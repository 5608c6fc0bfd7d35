"""Per-vertex tangents on the GPU for anisotropic renderers (``banks``, ``reference`` model=banks).

The scene keeps its meshes GPU-free and the shared :class:`GpuMesh` holds only
positions and normals; a method that needs tangents owns one more vertex
buffer per reflector mesh and tangent field (scene/tangents.py), and one
vertex array per program that reads ``in_position``, ``in_normal`` and
``in_tangent`` from the two buffers with the mesh's index buffer.
"""

from __future__ import annotations

import moderngl
import numpy as np

from envstudio.scene.tangents import TangentField, Tangents, mesh_tangents
from envstudio.shading.gpu_scene import GpuNode


class TangentBuffers:
    """Tangent vertex buffers and vertex arrays, cached by mesh and field.

    Parameters
    ----------
    ctx
        The context of the scene's meshes.
    """

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self._buffers: dict[tuple, tuple[moderngl.Buffer, Tangents]] = {}
        self._vaos: dict[tuple, moderngl.VertexArray] = {}

    def tangents(self, gpu_node: GpuNode, field: TangentField) -> Tangents:
        """The tangents of ``gpu_node``'s mesh under ``field`` (computed and uploaded once)."""
        return self._entry(gpu_node, field)[1]

    def render(self, program: moderngl.Program, gpu_node: GpuNode, field: TangentField) -> None:
        """Draw ``gpu_node`` with ``program``, ``in_tangent`` from ``field``."""
        buffer, _ = self._entry(gpu_node, field)
        vao_key = (_key(gpu_node, field), program.glo)
        vao = self._vaos.get(vao_key)
        if vao is None:
            mesh = gpu_node.mesh
            names = [n for n in ("in_position", "in_normal") if n in program]
            layout = " ".join("3f" if n in names else "12x" for n in ("in_position", "in_normal"))
            content = [(mesh.vbo, layout, *names)]
            if "in_tangent" in program:
                content.append((buffer, "3f", "in_tangent"))
            vao = self.ctx.vertex_array(
                program, content, index_buffer=mesh.ibo, index_element_size=4
            )
            self._vaos[vao_key] = vao
        vao.render(moderngl.TRIANGLES)

    def _entry(self, gpu_node: GpuNode, field: TangentField) -> tuple[moderngl.Buffer, Tangents]:
        key = _key(gpu_node, field)
        entry = self._buffers.get(key)
        if entry is None:
            tangents = mesh_tangents(gpu_node.node.mesh, field)
            buffer = self.ctx.buffer(np.ascontiguousarray(tangents.vectors, np.float32).tobytes())
            entry = self._buffers[key] = (buffer, tangents)
        return entry

    def forget_unused(self, gpu_nodes: list[GpuNode]) -> None:
        """Release what belongs to meshes no longer in ``gpu_nodes`` (after a scene change)."""
        live = {_key(g, None)[:2] for g in gpu_nodes}
        for key in [k for k in self._vaos if k[0][:2] not in live]:
            self._vaos.pop(key).release()
        for key in [k for k in self._buffers if k[:2] not in live]:
            self._buffers.pop(key)[0].release()

    def release(self) -> None:
        """Free every buffer and vertex array; safe to call twice."""
        self.forget_unused([])


def _key(gpu_node: GpuNode, field: TangentField | None) -> tuple:
    """The GPU mesh, its scene mesh (ids are reused after a release: both must match) and field."""
    return (id(gpu_node.mesh), id(gpu_node.node.mesh), field)
