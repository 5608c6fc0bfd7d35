"""Diffuse accuracy of kautz against the reference on every shipped map (issue #4).

For each map and each SH setting, ``envstudio compare`` renders an icosphere (nothing occludes)
with a diffuse material (k_d = 1, f_λ = 0, per-pixel evaluation) by the reference and by kautz;
this script then reads the two EXRs and measures the relative luminance error where
cos θ > 0.7, where Schlick's F = (1 − cos θ)^5 < 0.3 % leaves the glossy term out, so the error
is the irradiance error. Usage (from the checkout root, ≈ 1 min per map and setting on llvmpipe):

    python studies/kautz-border-and-sun/diffuse_accuracy.py OUT_DIR [--max-samples N]

Prints a Markdown table; each compare's own report stays in OUT_DIR.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import trimesh

from envstudio.core.env_sampling import LUMINANCE
from envstudio.io.images import read_image
from envstudio.resources import asset_root
from envstudio.scene.camera import OrbitCamera

SETTINGS = ((9, 0), (49, 32))
SIZE = 96
MIN_COS = 0.7
STUDIO_CAMERA = OrbitCamera(azimuth=115.0, elevation=20.0, distance=3.2, fov_y=45.0)


def sphere_cosines(camera: OrbitCamera, size: int) -> np.ndarray:
    """(size, size) cos θ between the unit sphere's normal and the view ray, NaN off the sphere."""
    inv = np.linalg.inv(camera.projection_matrix(1.0) @ camera.view_matrix())
    coords = (np.arange(size) + 0.5) / size * 2 - 1
    x, y = np.meshgrid(coords, -coords)
    ends = [np.stack([x, y, np.full_like(x, z), np.ones_like(x)], -1) @ inv.T for z in (-1, 1)]
    origin = ends[0][..., :3] / ends[0][..., 3:]
    direction = ends[1][..., :3] / ends[1][..., 3:] - origin
    direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
    b = np.sum(origin * direction, -1)
    disc = b * b - (np.sum(origin * origin, -1) - 1.0)
    t = -b - np.sqrt(np.where(disc > 0, disc, np.nan))
    normal = origin + t[..., None] * direction
    return -np.sum(normal * direction, -1)


def run(out: Path, max_samples: int) -> None:
    sphere = out / "icosphere.obj"
    trimesh.creation.icosphere(subdivisions=5, radius=1.0).export(sphere)
    inner = sphere_cosines(STUDIO_CAMERA, SIZE) > MIN_COS
    rows = []
    for env in sorted((asset_root() / "hdr").glob("*.exr")):
        cells = []
        for coefficients, lights in SETTINGS:
            folder = out / f"{env.stem}_{coefficients}_{lights}"
            params = {
                "kd": 1,
                "fresnel": 0,
                "trace": "false",
                "per_pixel": "true",
                "sh_coefficients": coefficients,
                "lights": lights,
                "max_samples": max_samples,
            }
            command = ["envstudio", "compare", "--methods", "kautz", "--env", str(env)]
            command += ["--mesh", str(sphere), "--size", f"{SIZE}x{SIZE}", "--out", str(folder)]
            for name, value in params.items():
                command += ["--param", f"{name}={value}"]
            subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
            report = json.loads((folder / "compare.json").read_text())
            y_ref = read_image(folder / "reference.exr")[..., :3] @ LUMINANCE
            y_kautz = read_image(folder / "kautz.exr")[..., :3] @ LUMINANCE
            relative = np.abs(y_kautz - y_ref)[inner] / y_ref[inner]
            kautz = report["methods"]["kautz"]
            cells.append(
                f"{kautz['psnr_db']:.1f} dB / {kautz['flip']:.3f}, "
                f"{100 * relative.mean():.2f} % / {100 * relative.max():.1f} %"
            )
        ref = report["reference"]
        noise = f"{100 * ref['rms_change']:.2f} %, {ref['samples']} spp"
        rows.append(f"| {env.stem} ({noise}) | " + " | ".join(cells) + " |")
    header = " | ".join(f"{c} / {k}" for c, k in SETTINGS)
    print(f"| map (reference half-change, spp) | {header} |")
    print("| --- | " + " | ".join("---" for _ in SETTINGS) + " |")
    print("\n".join(rows))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="folder for the compare reports")
    parser.add_argument("--max-samples", type=int, default=8192)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    run(args.out, args.max_samples)
    return 0


if __name__ == "__main__":
    sys.exit(main())
