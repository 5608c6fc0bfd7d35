"""The reference's GPU ray tracer (BVH in GLSL) against Embree on the room scene."""

import moderngl
import numpy as np
import trimesh
from trimesh.ray.ray_pyembree import RayMeshIntersector

from envstudio.core.bvh import build_bvh, intersect
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.io.scene_file import load_scene
from envstudio.methods.context import GpuScene
from envstudio.methods.tracing import TraceData, scene_triangles

SIDE = 32  # 1024 rays


def random_rays(rng, count):
    origins = rng.uniform(-1.5, 1.5, (count, 3)) * [1.0, 0.4, 1.0]
    directions = rng.normal(size=(count, 3))
    return origins, directions / np.linalg.norm(directions, axis=1, keepdims=True)


def test_gpu_bvh_hits_match_embree(gl_ctx, programs):
    scene = GpuScene(gl_ctx, programs, load_scene("room"), cube_size=16)
    positions, _, _ = scene_triangles(scene)
    trace = TraceData(gl_ctx, scene)
    origins, directions = random_rays(np.random.default_rng(7), SIDE * SIDE)

    def texture(array):
        data = np.ascontiguousarray(array.reshape(SIDE, SIDE, 3), dtype=np.float32)
        tex = gl_ctx.texture((SIDE, SIDE), 3, data.tobytes(), dtype="f4")
        tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        return tex

    # with the stack the reference compiles for this scene (BVH depth + 2)
    program = programs.get("testing/trace_probe.glsl", {"TRACE_STACK": trace.stack_size})
    trace.bind(program)
    texture(origins).use(location=2)
    texture(directions).use(location=3)
    program["u_origins"].value = 2
    program["u_directions"].value = 3
    target = gl_ctx.texture((SIDE, SIDE), 4, dtype="f4")
    gl_ctx.framebuffer([target]).use()
    gl_ctx.viewport = (0, 0, SIDE, SIDE)
    FullscreenPass(gl_ctx).draw(program)
    out = np.frombuffer(target.read(), np.float32).reshape(-1, 4)

    mesh = trimesh.Trimesh(
        positions.reshape(-1, 3), np.arange(len(positions) * 3).reshape(-1, 3), process=False
    )
    embree = RayMeshIntersector(mesh)
    first = embree.intersects_first(origins, directions)
    hit = first >= 0
    assert hit.mean() > 0.95, "rays start inside the room, nearly all hit something"
    np.testing.assert_array_equal(out[:, 3] > 0, hit)
    gpu_triangle = trace.bvh.order[out[hit, 1].astype(int)]
    agree = gpu_triangle == first[hit]
    assert agree.mean() > 0.995, f"{(~agree).sum()} rays hit another triangle than Embree's"
    locations, ray_ids, _ = embree.intersects_location(origins, directions, multiple_hits=False)
    embree_t = np.full(len(origins), np.inf)
    embree_t[ray_ids] = np.linalg.norm(locations - origins[ray_ids], axis=1)
    np.testing.assert_allclose(out[hit, 0], embree_t[hit], rtol=1e-3, atol=1e-4)
    trace.release()
    scene.release()


def test_cpu_bvh_twin_matches_embree():
    rng = np.random.default_rng(3)
    scene = load_scene("room")
    tris = []
    for node in scene.nodes:
        m = node.transform.matrix().astype(np.float64)
        world = node.mesh.positions @ m[:3, :3].T + m[:3, 3]
        tris.append(world[node.mesh.indices])
    tris = np.concatenate(tris)
    bvh = build_bvh(tris)
    origins, directions = random_rays(rng, 100)
    mesh = trimesh.Trimesh(tris.reshape(-1, 3), np.arange(len(tris) * 3).reshape(-1, 3))
    first = RayMeshIntersector(mesh).intersects_first(origins, directions)
    ours = [intersect(bvh, tris, o, d)[1] for o, d in zip(origins, directions, strict=True)]
    np.testing.assert_array_equal(ours, first)


def median_split_depth(count: int, leaf_size: int = 4) -> int:
    return 0 if count <= leaf_size else 1 + median_split_depth(count - count // 2, leaf_size)


def test_bvh_depth_is_that_of_the_median_split():
    rng = np.random.default_rng(5)
    for count in (1, 4, 5, 9, 100, 1000, 3674):
        tris = rng.uniform(-1.0, 1.0, (count, 3, 3))
        assert build_bvh(tris).depth == median_split_depth(count)
