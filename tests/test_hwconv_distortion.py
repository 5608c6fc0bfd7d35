"""Seed 004 Figure 3 (method hwconv, no GL): a paraboloid kernel's distortion on the sphere."""

import numpy as np
import pytest
from matplotlib.figure import Figure

from envstudio.cli import main
from envstudio.methods.hwconv.distortion import analytic_distortion, kernel_distortion
from envstudio.methods.hwconv.radii import plan_filters
from test_bad_input import assert_one_line_error, run_cli


@pytest.mark.parametrize("radius", [0.05, 0.2, 0.5, 1.0])
@pytest.mark.parametrize("distance", [0.0, 0.3, 0.7, 1.0])
def test_projected_border_matches_the_closed_form(radius, distance):
    """Border points projected by core.paraboloid against e(r, d) of the module docstring."""
    assert kernel_distortion(radius, distance) == pytest.approx(
        analytic_distortion(radius, distance), rel=1e-9, abs=1e-12
    )


def test_distortion_goes_up_to_25_percent_for_the_largest_kernel():
    """§5.2: "the distortion goes up to 25 % for large radii"; zero at the centre, ≈ r d/(1+d²)."""
    r, d = np.meshgrid(np.linspace(0.01, 0.5, 50), np.linspace(0.0, 1.0, 101))
    e = analytic_distortion(r, d)
    assert np.all(e[0] < 1e-12) and np.all(np.diff(e, axis=0) > 0)  # grows from centre to rim
    assert e.max() == pytest.approx(np.arctan(0.125) / np.arctan(1 / 1.75))  # e(0.5, 1)
    assert e.max() == pytest.approx(0.2395, abs=1e-4)
    np.testing.assert_allclose(analytic_distortion(1e-3, d), 1e-3 * d / (1 + d * d), rtol=1e-5)
    # The largest kernel of the paper's table: map L's r_l at N = 10, on the rim.
    r_l = plan_filters(10, 0.1, 512, 64).radius_large / 256
    assert kernel_distortion(r_l, 1.0) == pytest.approx(0.242, abs=1e-3)


def test_figure_is_a_png_written_atomically(tmp_path, capsys, monkeypatch):
    out = tmp_path / "fig3.png"
    assert main(["figure", "hwconv-distortion", "-o", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "largest e 24.0 %" in capsys.readouterr().out
    assert [p.name for p in tmp_path.iterdir()] == ["fig3.png"]
    before = out.read_bytes()

    def fail(self, *args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(Figure, "savefig", fail)
    capsys.readouterr()
    assert main(["figure", "hwconv-distortion", "-o", str(out)]) == 2  # one line, no traceback
    assert "fig3.png: not written (disk full); the existing fig3.png is unchanged" in (
        capsys.readouterr().err
    )
    assert out.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["fig3.png"]


def test_figure_needs_a_png_in_an_existing_folder(tmp_path, capsys):
    status, err = run_cli(capsys, "figure", "hwconv-distortion", "-o", str(tmp_path / "x.jpg"))
    assert_one_line_error(status, err, "expected a .png file name")
    status, err = run_cli(capsys, "figure", "hwconv-distortion", "-o", str(tmp_path / "no/x.png"))
    assert_one_line_error(status, err, "does not exist")
