"""Render the icon's PNG sizes from ``envstudio.svg`` (cairosvg, a Python SVG rasteriser).

``build_bundle.py`` calls :func:`render_pngs` for the bundle's hicolor icons; run as a script
it refreshes the committed copies in ``packaging/linux/icons/`` (``SIZE.png``), which the
bundle uses where cairosvg (or the libcairo it needs) is missing::

    python -m pip install cairosvg   # any venv; libcairo2 from the system
    python packaging/linux/render_icons.py
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
SIZES = (16, 24, 32, 48, 64, 128, 256, 512)


def _rasteriser():
    try:
        import cairosvg
    except (ImportError, OSError):  # OSError: cairocffi without the system's libcairo
        return None
    return cairosvg


def render_pngs(svg: Path, hicolor: Path, app_id: str, sizes=SIZES) -> bool:
    """Write ``hicolor/NxN/apps/APP_ID.png`` for each size; False when cairosvg is unavailable."""
    cairosvg = _rasteriser()
    if cairosvg is None:
        return False
    for size in sizes:
        folder = hicolor / f"{size}x{size}" / "apps"
        folder.mkdir(parents=True, exist_ok=True)
        cairosvg.svg2png(
            url=str(svg),
            write_to=str(folder / f"{app_id}.png"),
            output_width=size,
            output_height=size,
        )
    return True


def main() -> int:
    cairosvg = _rasteriser()
    if cairosvg is None:
        print("render_icons: cairosvg is not importable (pip install cairosvg)", file=sys.stderr)
        return 1
    out = HERE / "icons"
    out.mkdir(exist_ok=True)
    for size in SIZES:
        cairosvg.svg2png(
            url=str(HERE / "envstudio.svg"),
            write_to=str(out / f"{size}.png"),
            output_width=size,
            output_height=size,
        )
        print(out / f"{size}.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
