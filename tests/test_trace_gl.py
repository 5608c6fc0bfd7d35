"""The reference's GPU ray tracer (BVH in GLSL) against Embree on the room scene."""

import moderngl
import numpy as np
import pytest
import trimesh
from trimesh.ray.ray_pyembree import RayMeshIntersector

from envstudio.core.bvh import build_bvh, intersect
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.io.scene_file import load_scene
from envstudio.methods.reference.tracing import TraceData, scene_triangles
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene
from envstudio.scene.mesh import MeshData
from envstudio.shading.gpu_scene import GpuScene

RAYS = 1024


def random_rays(rng, count):
    origins = rng.uniform(-1.5, 1.5, (count, 3)) * [1.0, 0.4, 1.0]
    directions = rng.normal(size=(count, 3))
    return origins, directions / np.linalg.norm(directions, axis=1, keepdims=True)


def probe_closest_hits(gl_ctx, programs, trace, origins, directions, stack_size):
    """(n, 4) of testing/trace_probe.glsl for n rays: t, triangle, 0, hit."""

    def texture(array):
        data = np.ascontiguousarray(array.reshape(1, -1, 3), dtype=np.float32)
        tex = gl_ctx.texture((data.shape[1], 1), 3, data.tobytes(), dtype="f4")
        tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        return tex

    program = programs.get("testing/trace_probe.glsl", {"TRACE_STACK": stack_size})
    trace.bind(program)
    inputs = texture(origins), texture(directions)
    inputs[0].use(location=2)
    inputs[1].use(location=3)
    program["u_origins"].value = 2
    program["u_directions"].value = 3
    target = gl_ctx.texture((len(origins), 1), 4, dtype="f4")
    framebuffer = gl_ctx.framebuffer([target])
    framebuffer.use()
    gl_ctx.viewport = (0, 0, len(origins), 1)
    FullscreenPass(gl_ctx).draw(program)
    out = np.frombuffer(target.read(), np.float32).reshape(-1, 4).copy()
    for obj in (*inputs, framebuffer, target):
        obj.release()
    return out


def test_gpu_bvh_hits_match_embree(gl_ctx, programs):
    scene = GpuScene(gl_ctx, programs, load_scene("room"), cube_size=16)
    positions, _, _ = scene_triangles(scene)
    trace = TraceData(gl_ctx, scene)
    origins, directions = random_rays(np.random.default_rng(7), RAYS)
    # with the stack the reference compiles for this scene (BVH depth + 2)
    out = probe_closest_hits(gl_ctx, programs, trace, origins, directions, trace.stack_size)

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


def test_a_ray_through_every_box_of_a_deep_path_fits_the_traversal_stack(gl_ctx, programs):
    # 1024 triangles in a row along x: the median splits cut along x, and a ray
    # along the row enters both children of every node on its way to the first
    # leaf, deferring one sibling per level: the most the near-first walk holds
    count = 1024
    x = np.repeat(np.arange(count, dtype=np.float32) * 0.01, 3)
    corners = np.tile(np.array([[0.0, -1.0, -1.0], [0.0, 2.0, -1.0], [0.0, -1.0, 2.0]]), (count, 1))
    corners[:, 0] = x
    normals = np.tile([[-1.0, 0.0, 0.0]], (3 * count, 1))
    row = MeshData(corners, normals, np.arange(3 * count, dtype=np.uint32).reshape(-1, 3), "row")
    scene = GpuScene(
        gl_ctx,
        programs,
        Scene(Environment.constant([1.0, 1.0, 1.0]), [Node("row", row)]),
        cube_size=16,
    )
    trace = TraceData(gl_ctx, scene)
    assert trace.bvh.depth == median_split_depth(count) == 8
    origin, direction = np.array([[-1.0, 0.0, 0.0]]), np.array([[1.0, 0.0, 0.0]])
    # depth + 1 entries are the most it holds; the reference compiles depth + 2
    for stack_size in (trace.bvh.depth + 1, trace.stack_size):
        hit = probe_closest_hits(gl_ctx, programs, trace, origin, direction, stack_size)[0]
        assert hit[3] == 1.0 and hit[0] == pytest.approx(1.0), f"stack {stack_size}: {hit}"
        assert corners[3 * trace.bvh.order[int(hit[1])], 0] == 0.0
    # one entry short (depth), the near child of the last split is dropped: a farther hit
    short = probe_closest_hits(gl_ctx, programs, trace, origin, direction, trace.bvh.depth)[0]
    assert short[0] > 1.0 + 1e-3, "the row does not fill the stack: the test proves nothing"
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
