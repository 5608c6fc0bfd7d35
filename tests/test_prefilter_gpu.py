"""The GPU Phong cube mip chain (prefilter.chain_gpu, issue 14): FIS against the brute force.

Tolerances are the errors measured on these maps with the default samples
(studies/prefilter-speed/README.md, "The chain on the GPU"), with a margin of about 1.5.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from envstudio.cli import main
from envstudio.core import cubemap, latlong
from envstudio.prefilter import brute_force, kernels
from envstudio.prefilter.chain import prefiltered_chain
from envstudio.prefilter.chain_gpu import (
    DEFAULT_SAMPLES,
    MAX_SAMPLES,
    gpu_prefiltered_chain,
    level_samples,
    lobe_samples,
)
from envstudio.resources import asset_root

SUNRISE = str(asset_root() / "hdr" / "sunrise.exr")


def smooth_map(height: int, seed: int) -> np.ndarray:
    """A positive, smooth random lat-long map (tests/test_prefilter.py's): exp of a polynomial."""
    rng = np.random.default_rng(seed)
    d = latlong.texel_directions(height)
    a, b = rng.normal(size=(2, 3, 3))
    return np.exp(d @ a + 0.7 * (d @ b) ** 2).astype(np.float32)


def max_of_mean(got: np.ndarray, want: np.ndarray) -> float:
    return float(np.abs(got - want).max() / want.mean())


def test_lobe_samples_follow_the_phong_lobe():
    for exponent in (2.0, 100.0):
        table = lobe_samples(exponent, 4096)
        assert np.allclose(np.linalg.norm(table[:, :3], axis=1), 1.0, atol=1e-6)
        # E[cos θ] under (N + 1)/2π cos^N θ is (N + 1)/(N + 2); E[l_x] = E[l_y] = 0.
        assert abs(table[:, 2].mean() - (exponent + 1) / (exponent + 2)) < 1e-4
        assert np.abs(table[:, :2].mean(axis=0)).max() < 2e-3
        # FIS: the level grows as the pdf falls, by ½ log2 of the pdf ratio.
        pdf = (exponent + 1) / (2 * math.pi) * table[:, 2].astype(np.float64) ** exponent
        assert np.allclose(table[:, 3], 0.5 * np.log2(1 / (4096 * pdf)), atol=1e-4)
    assert level_samples(256, 0) == 256 and level_samples(256, 3) == 2048
    assert level_samples(256, 10) == MAX_SAMPLES


def test_gpu_chain_level_zero_matches_the_brute_force(gl_ctx, programs):
    image = smooth_map(64, seed=4)
    chain = gpu_prefiltered_chain(gl_ctx, programs, image, 8, 4, 4.0, 1.0)
    assert [level.faces.shape for level in chain] == [(6, n, n, 3) for n in (8, 4, 2, 1)]
    assert chain[0].exponent == 32.0 and chain[0].source_rows == 64
    brute = brute_force.prefilter(image, cubemap.texel_directions(8), kernels.phong(32.0))
    assert max_of_mean(chain[0].faces, brute) < 0.04  # measured 0.027


def test_gpu_and_cpu_chains_agree_on_a_smooth_map(gl_ctx, programs):
    image = smooth_map(64, seed=4)
    gpu = gpu_prefiltered_chain(gl_ctx, programs, image, 8, 4, 4.0, 1.0)
    cpu = prefiltered_chain(image, 8, 4, 4.0, 1.0)
    errors = [max_of_mean(g.faces, c.faces) for g, c in zip(gpu, cpu, strict=True)]
    # Measured 0.027, 0.008, 0.003, 0.001 (N = 32, 12.7, 5.0, 2): more samples as lobes widen.
    assert errors[0] < 0.04 and max(errors[1:]) < 0.012, errors


def test_gpu_chain_keeps_a_constant_map_constant(gl_ctx, programs):
    image = np.full((32, 64, 3), 2.5, dtype=np.float32)
    chain = gpu_prefiltered_chain(gl_ctx, programs, image, 8, 4, 10.0, 1.0, samples=32)
    for level in chain:
        assert np.allclose(level.faces, 2.5, rtol=1e-5), level.exponent


def test_gpu_chain_on_a_cube_source(gl_ctx, programs):
    image = smooth_map(64, seed=5)
    gpu = gpu_prefiltered_chain(gl_ctx, programs, image, 8, 2, 4.0, 1.0, source_kind="cube")
    brute = brute_force.prefilter(image, cubemap.texel_directions(8), kernels.phong(32.0))
    assert max_of_mean(gpu[0].faces, brute) < 0.11  # measured 0.076: resampled once more


@pytest.mark.parametrize("device", ["gpu", "cpu"])
def test_chain_command_device(tmp_path, capsys, device):
    argv = ["prefilter", "--chain", "--env", SUNRISE, "--param", "cube", "--size", "8",
            "--levels", "2", "--source-height", "32", "--device", device,
            "-o", str(tmp_path / "c.dds")]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert ("on the GPU" in out) == (device == "gpu") and ("on the CPU" in out) == (device == "cpu")
    assert (tmp_path / "c.dds").is_file()


def test_chain_command_rejects_a_bad_sample_count(tmp_path, capsys):
    argv = ["prefilter", "--chain", "--env", SUNRISE, "--param", "cube", "--samples", "0",
            "-o", str(tmp_path / "c.dds")]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "--samples 0" in err and "1..16384" in err and len(err.splitlines()) == 1
    assert not list(tmp_path.iterdir())
    assert DEFAULT_SAMPLES == 256


def test_split_levels_give_the_unsplit_result(gl_ctx, programs, monkeypatch):
    """Sharing a texel's samples among f × f fragments changes only the order of the sum."""
    from envstudio.prefilter import chain_gpu

    assert chain_gpu.split_factor(512, 256) == 1 and chain_gpu.split_factor(1, 4096) == 64
    assert all(chain_gpu.split_factor(m, 256) ** 2 <= 256 for m in (1, 2, 8, 64))
    image = smooth_map(64, seed=6)
    split = gpu_prefiltered_chain(gl_ctx, programs, image, 16, 5, 6.0, 1.0, samples=64)
    monkeypatch.setattr(chain_gpu, "SPLIT_EDGE", 1)
    whole = gpu_prefiltered_chain(gl_ctx, programs, image, 16, 5, 6.0, 1.0, samples=64)
    for a, b in zip(split, whole, strict=True):
        assert np.allclose(a.faces, b.faces, rtol=1e-5), a.exponent
