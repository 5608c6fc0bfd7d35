"""The scene's triangles on the GPU for ray tracing (BVH of core/bvh.py).

Layout (read by shaders/reference/trace.glsl), two shader storage buffers of
float32 vec4 (OpenGL 4.3), at binding points :data:`NODE_BINDING` and
:data:`TRIANGLE_BINDING`: nodes take 2 — (min.xyz, right child or first
triangle), (max.xyz, triangle count) — and triangles 7 — v0, v1, v2, n0, n1,
n2, (albedo.rgb, kind) with kind 0 for local diffuse objects and 1 for
reflectors. Positions and normals are in world space.
"""

from __future__ import annotations

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.bvh import FlatBVH, build_bvh
from envstudio.plugin import GpuScene, set_uniform

NODE_BINDING = 0
TRIANGLE_BINDING = 1
#: Reflector hits a traced path continues through (sampling the material, reference/paths.glsl)
#: before it returns black.
TRACE_BOUNCES = 3


def scene_triangles(
    scene: GpuScene,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float32]]:
    """World-space triangles of every node.

    Returns
    -------
    positions : (m, 3, 3) float64
    normals : (m, 3, 3) float64
        Unit vertex normals per corner.
    info : (m, 4) float32
        Albedo RGB and kind (0 local, 1 reflector) per triangle.
    """
    positions, normals, info = [], [], []
    for gpu_node in scene.nodes:
        mesh = gpu_node.node.mesh
        model = gpu_node.model.astype(np.float64)
        world = mesh.positions @ model[:3, :3].T + model[:3, 3]
        n = mesh.normals @ gpu_node.normal.astype(np.float64).T
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        positions.append(world[mesh.indices])
        normals.append(n[mesh.indices])
        kind = 1.0 if gpu_node.node.role == "reflector" else 0.0
        row = np.array([*gpu_node.node.color, kind], dtype=np.float32)
        info.append(np.broadcast_to(row, (mesh.triangle_count, 4)))
    return np.concatenate(positions), np.concatenate(normals), np.concatenate(info)


class TraceData:
    """BVH and triangle buffers of a :class:`GpuScene`.

    Parameters
    ----------
    ctx
        Context owning the buffers.
    scene
        Scene whose nodes (with their current transforms) are traced.
    """

    def __init__(self, ctx: moderngl.Context, scene: GpuScene):
        positions, normals, info = scene_triangles(scene)
        self.bvh: FlatBVH = build_bvh(positions)
        order = self.bvh.order
        nodes = np.empty((self.bvh.node_count, 2, 4), dtype=np.float32)
        nodes[:, 0, :3] = self.bvh.bounds_min
        nodes[:, 0, 3] = self.bvh.right_or_first
        nodes[:, 1, :3] = self.bvh.bounds_max
        nodes[:, 1, 3] = self.bvh.count
        tris = np.zeros((len(order), 7, 4), dtype=np.float32)
        tris[:, 0:3, :3] = positions[order]
        tris[:, 3:6, :3] = normals[order]
        tris[:, 6] = info[order]
        self.nodes = ctx.buffer(nodes.tobytes())
        self.triangles = ctx.buffer(tris.tobytes())
        extent = positions.reshape(-1, 3).max(axis=0) - positions.reshape(-1, 3).min(axis=0)
        self.ray_offset = float(1e-4 * np.linalg.norm(extent))
        self.triangle_count = len(order)
        # The near-first traversal of trace.glsl holds at most one deferred sibling per
        # level below the root plus the near child: depth + 1 entries, one more to spare.
        self.stack_size = self.bvh.depth + 2

    def bind(self, program: moderngl.Program) -> None:
        """Bind both buffers to their binding points and set ``program``'s trace uniforms."""
        self.nodes.bind_to_storage_buffer(NODE_BINDING)
        self.triangles.bind_to_storage_buffer(TRIANGLE_BINDING)
        set_uniform(program, "u_ray_offset", self.ray_offset)
        set_uniform(program, "u_trace_bounces", TRACE_BOUNCES)

    def release(self) -> None:
        """Free the buffers; safe to call twice."""
        for buffer in (self.nodes, self.triangles):
            if buffer is not None:
                buffer.release()
        self.nodes = self.triangles = None
