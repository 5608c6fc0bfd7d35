"""Environment importance sampling: the NumPy tables and the GPU sampler agree."""

import numpy as np

from envstudio.core import latlong
from envstudio.core.env_sampling import EnvironmentDistribution, luminance
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.io.images import read_environment
from envstudio.methods.reference.environment_tables import EnvironmentTables
from envstudio.resources import asset_root


def test_importance_sampling_is_unbiased_on_a_sun_dominated_map():
    img = read_environment(asset_root() / "hdr" / "sunrise.exr")[::4, ::4]
    dist = EnvironmentDistribution.from_latlong(img)
    dirs, pdf = dist.sample(np.random.default_rng(1).random((200_000, 2)))
    uv = latlong.direction_to_uv(dirs)
    h, w = img.shape[:2]
    texel = img[
        np.minimum((uv[:, 1] * h).astype(int), h - 1), np.minimum((uv[:, 0] * w).astype(int), w - 1)
    ]
    estimate = np.mean(luminance(texel) / pdf)
    exact = np.sum(luminance(img) * latlong.texel_solid_angles(h, w))
    assert abs(estimate / exact - 1) < 0.01
    # luminance importance: the estimator's relative spread is small despite the sun
    assert np.std(luminance(texel) / pdf) / estimate < 0.5


def test_gpu_sampler_follows_the_tables(gl_ctx, programs):
    img = np.full((16, 32, 3), 0.01, np.float32)
    img[5, 7] = 50.0
    img[10, 20] = 25.0
    tables = EnvironmentTables(gl_ctx, img)
    program = programs.get("testing/env_sampling_probe.glsl")
    tables.bind(program, 1)
    target = gl_ctx.texture((128, 128), 4, dtype="f4")
    gl_ctx.framebuffer([target]).use()
    gl_ctx.viewport = (0, 0, 128, 128)
    FullscreenPass(gl_ctx).draw(program)
    out = np.frombuffer(target.read(), np.float32).reshape(-1, 4).astype(np.float64)
    dist = EnvironmentDistribution.from_latlong(img)
    uv = latlong.direction_to_uv(out[:, :3])
    rows = np.minimum((uv[:, 1] * 16).astype(int), 15)
    cols = np.minimum((uv[:, 0] * 32).astype(int), 31)
    share = np.bincount(rows * 32 + cols, minlength=512) / len(out)
    expected = (dist.weights / dist.weights.sum()).ravel()
    assert abs(share[5 * 32 + 7] - expected[5 * 32 + 7]) < 0.01
    assert abs(share[10 * 32 + 20] - expected[10 * 32 + 20]) < 0.01
    # the GPU pdf is the tables' pdf (a sample exactly on a texel edge may round either way)
    agree = np.isclose(out[:, 3], dist.pdf(out[:, :3]), rtol=1e-3)
    assert agree.mean() > 0.999
    tables.release()
