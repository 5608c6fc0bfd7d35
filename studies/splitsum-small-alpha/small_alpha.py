"""The GL split sum against a NumPy split sum at small α, by ``chain_size`` (issue #30).

studies/splitsum-small-alpha/README.md's "GL split sum vs NumPy split sum" column, re-created:
40 random pixels
(seed 0) with n·v > 0.3 of a sphere (by default the scene files' ``primitive = "sphere"``,
radius 0.5, 48 rings, at the studio camera: azimuth 115°, elevation 20°, distance 3.2, 45°
field of view) under ``studio.exr`` box-filtered to ROWS × 2 ROWS for both sides, ``splitsum`` at
f0 = 1, k_d = 0, single scattering, against the same sum in NumPy over every texel with
its exact solid angle: the ⟨r, l⟩-weighted D(h)/4 lobe about r (n = v = r), normalised,
at the two levels' α_k that α lies between, blended as the method blends them (a level of
α_k = 0 is the environment itself, read as the texel along r), times A + B from the DFG
quadrature. It prints the median of |GL / NumPy − 1| and, beside it, of |NumPy split sum /
GGX integral − 1| (the split sum's own error). Usage (from the checkout root, seconds on
llvmpipe at 48² and 128 rows):

    python studies/splitsum-small-alpha/small_alpha.py [--alpha A] [--rows ROWS] [--size EDGE] \
        [--radius R] [--camera AZ,EL,DIST] [--chain-size 128 256 ...]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from envstudio.engine.session import RenderSession
from envstudio.io.images import read_image
from envstudio.methods.splitsum.method import level_alphas
from envstudio.prefilter.brute_force import downsample_latlong
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene
from envstudio.scene.primitives import uv_sphere

# the tests' independent NumPy sum (tests/splitsum_numpy_reference.py)
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from splitsum_numpy_reference import ggx_integral_and_split_sum

STUDIO = Path(__file__).resolve().parents[2] / "assets" / "hdr" / "studio.exr"


def sphere_pixels(
    camera: OrbitCamera, edge: int, radius: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(edge, edge) hit mask and (edge, edge, 3) unit normals and views of the sphere."""
    inv = np.linalg.inv(
        camera.projection_matrix(1.0).astype(np.float64) @ camera.view_matrix().astype(np.float64)
    )
    x = (np.arange(edge) + 0.5) / edge * 2 - 1
    X, Y = np.meshgrid(x, -x)  # row 0 at the top
    ends = [np.stack([X, Y, np.full_like(X, z), np.ones_like(X)], -1) @ inv.T for z in (-1, 1)]
    origin, far = (e[..., :3] / e[..., 3:] for e in ends)
    direction = far - origin
    origin = origin / radius
    direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
    b = np.sum(origin * direction, -1)
    disc = b * b - np.sum(origin * origin, -1) + 1.0
    hit = disc > 0
    normal = origin + (-b - np.sqrt(np.where(hit, disc, 0.0)))[..., None] * direction
    return hit, normal, -direction


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--alpha", type=float, default=0.02)
    parser.add_argument("--rows", type=int, default=128, help="rows of the box-filtered map")
    parser.add_argument("--size", type=int, default=48, help="image edge in pixels")
    parser.add_argument("--radius", type=float, default=0.5, help="sphere radius")
    parser.add_argument("--camera", default="115,20,3.2", help="azimuth,elevation,distance")
    parser.add_argument("--chain-size", nargs="+", default=["128", "256"])
    args = parser.parse_args()
    full = read_image(STUDIO)
    radiance = full if args.rows >= full.shape[0] else downsample_latlong(full, args.rows)
    radiance = radiance.astype(np.float32)
    azimuth, elevation, distance = (float(x) for x in args.camera.split(","))
    camera = OrbitCamera(azimuth=azimuth, elevation=elevation, distance=distance, fov_y=45.0)
    sphere = Node("sphere", uv_sphere(args.radius))
    session = RenderSession(Scene(Environment(radiance), [sphere], camera), cube_size=256)
    hit, normal, view = sphere_pixels(session.camera, args.size, args.radius)
    pool = np.argwhere(hit & (np.sum(normal * view, -1) > 0.3))
    pick = pool[np.random.default_rng(0).choice(len(pool), 40, replace=False)]
    n, v = normal[pick[:, 0], pick[:, 1]], view[pick[:, 0], pick[:, 1]]
    method = session.method("splitsum")
    print(
        f"studio.exr at {radiance.shape[0]} rows, {args.size}² image, sphere of radius "
        f"{args.radius:g}, camera {args.camera}, alpha {args.alpha:g}"
    )
    for chain in args.chain_size:
        method.values.update(
            {"roughness": args.alpha, "fresnel": 1.0, "kd": 0.0, "multiscatter": False}
        )
        method.values.update({"chain_size": chain})
        session.renderer.display["background"] = False
        session.render_offscreen(method, (args.size, args.size))
        gl = session.read_hdr()[pick[:, 0], pick[:, 1]]
        truth, split = ggx_integral_and_split_sum(
            radiance.astype(np.float64), n, v, args.alpha, level_alphas(int(chain))
        )
        print(
            f"chain_size={chain} ({len(method._levels) + 1} levels, built in "
            f"{method.chain_seconds:.2f} s): GL vs NumPy split sum median "
            f"{100 * np.median(np.abs(gl / split - 1)):.1f} %; NumPy split sum vs GGX integral "
            f"{100 * np.median(np.abs(split / truth - 1)):.1f} %"
        )
    session.release()


if __name__ == "__main__":
    main()
