"""Option defaults valid whatever the other options' valid values (issue 38 item 3).

``prefilter --chain``'s ``--levels`` is as many as ``--size`` holds, up to 8; a map's
``--size`` (``prefilter``, ``envmap``) grows with a paraboloid ``--border`` that needs it.
"""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.cli import main
from envstudio.io.images import read_image, write_image


@pytest.fixture
def env(tmp_path):
    """A small smooth lat-long map."""
    rows = np.linspace(0.5, 2.0, 16, dtype=np.float32)[:, None, None]
    path = tmp_path / "env.exr"
    write_image(path, np.broadcast_to(rows, (16, 32, 3)).copy())
    return str(path)


@pytest.mark.parametrize(
    ("kernel", "size", "levels"),
    [("ggx", 64, 7), ("phong", 4, 3), ("ggx", 1, 1), ("phong", 256, 8)],
)
def test_a_chain_has_as_many_levels_as_its_size_holds_up_to_8(
    tmp_path, env, capsys, kernel, size, levels
):
    out = tmp_path / "chain.ktx2"
    argv = ["prefilter", "--env", env, "--chain", "--kernel", kernel, "--param", "cube"]
    assert main([*argv, "--size", str(size), "-o", str(out)]) == 0
    assert f": {levels} levels in " in capsys.readouterr().out


@pytest.mark.parametrize(("border", "size"), [(0, 128), (10, 128), (70, 142)])
def test_a_paraboloid_is_large_enough_for_its_border_by_default(tmp_path, env, border, size):
    out = tmp_path / "diffuse.exr"
    argv = ["prefilter", "--env", env, "--kernel", "diffuse", "--border", str(border)]
    assert main([*argv, "-o", str(out)]) == 0
    assert read_image(out).shape[:2] == (size, 2 * size)


@pytest.mark.parametrize(("border", "size"), [(0, 256), (140, 282)])
def test_envmap_is_large_enough_for_its_border_by_default(tmp_path, env, border, size):
    out = tmp_path / "paraboloid.exr"
    argv = ["envmap", "--env", env, "--to", "paraboloid", "--border", str(border)]
    assert main([*argv, "-o", str(out)]) == 0
    assert read_image(out).shape[:2] == (size, 2 * size)
