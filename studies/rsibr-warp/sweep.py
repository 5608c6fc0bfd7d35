"""Generated against directly baked radiance maps over a sweep of 80 views (studies/rsibr-warp).

Usage: ``python studies/rsibr-warp/sweep.py ENV.exr SIZE``. Views: 50 on a Fibonacci
sphere, the 20 icosahedron face centres and 10 edge midpoints. PSNR (peak: the
direct map's maximum) over the disc less one texel, and over rho < 0.45.
"""

import sys
import time

import numpy as np

from envstudio.core import icosahedron as ico
from envstudio.envmap.conversions import latlong_to_cube, read_texture, upload_latlong
from envstudio.gpu.context import create_headless_context
from envstudio.gpu.programs import ProgramLibrary
from envstudio.io.images import read_environment
from envstudio.methods.rsibr.generator import MapGenerator
from envstudio.methods.rsibr.gpu_bake import GpuBaker, bake_gpu
from envstudio.methods.rsibr.warp import view_frame

env_path, n = sys.argv[1], int(sys.argv[2])
ctx = create_headless_context()
programs = ProgramLibrary(ctx)
env = read_environment(env_path)
cube = latlong_to_cube(ctx, programs, upload_latlong(ctx, env), 256)
k = np.arange(50) + 0.5
phi = np.arccos(1 - 2 * k / 50)
theta = np.pi * (1 + 5**0.5) * k
fib = np.stack([np.cos(theta) * np.sin(phi), np.cos(phi), np.sin(theta) * np.sin(phi)], -1)
v12, f12 = ico.icosahedron()
edges = [(a, b) for a, b, c in f12[:10]]
mids = np.array([(v12[a] + v12[b]) / np.linalg.norm(v12[a] + v12[b]) for a, b in edges])
sweep = np.concatenate([fib, ico.face_centres(v12, f12), mids])
c = (np.arange(n) + 0.5) / n - 0.5
rho = np.hypot(*np.meshgrid(c, c))


def psnr(a, b, mask):
    mse = np.mean((a[mask] - b[mask]) ** 2)
    return 10 * np.log10(b[mask].max() ** 2 / mse)


for name, views in (("phong", 12), ("lambertian", 12), ("phong", 42), ("lambertian", 42)):
    t0 = time.perf_counter()
    bake = bake_gpu(ctx, programs, cube, "k", name, {}, n, views)
    t_bake = time.perf_counter() - t0
    texs = []
    for m in bake.maps:
        t = ctx.texture((n, n), 3, m.tobytes(), dtype="f4")
        t.repeat_x = t.repeat_y = False
        texs.append(t)
    gen = MapGenerator(ctx, programs, n)
    direct = GpuBaker(ctx, programs, n)
    for warp in (bake.warp, "normal" if bake.warp == "mirror" else "mirror"):
        for pp in (False, True):
            res = []
            for v in sweep:
                T = view_frame(v)
                g = read_texture(
                    gen.generate(texs, bake.views, bake.frames, bake.faces, T, warp, per_pixel=pp)
                )
                direct.render(cube, name, bake.parameters, T)
                d = read_texture(direct.texture)
                res.append((psnr(g, d, rho < 0.5 - 1 / n), psnr(g, d, rho < 0.45)))
            res = np.array(res)
            worst = np.argmin(res[:, 0])
            print(
                f"{name:10s} views={views} warp={warp:6s} per_pixel={pp!s:5s} "
                f"disc: median {np.median(res[:, 0]):.1f} dB worst {res[worst, 0]:.1f} dB "
                f"at v={np.round(sweep[worst], 3)} | rho<0.45: median "
                f"{np.median(res[:, 1]):.1f} worst {res[:, 1].min():.1f} (bake {t_bake:.1f}s)"
            )
    for t in texs:
        t.release()
    gen.release()
    direct.release()
