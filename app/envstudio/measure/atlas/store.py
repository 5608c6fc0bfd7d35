"""The atlas folder: its settings, one JSON file of rows per measured scene."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from envstudio.errors import ParameterError
from envstudio.io.atomic import write_text_atomic
from envstudio.measure.atlas.grid import AtlasGrid, SceneCell

__all__ = ["AtlasStore"]

_SETTINGS = "atlas-settings.json"
_CELLS = "cells"


class AtlasStore:
    """Rows of measured cells under ``folder/cells``, keyed by scene.

    Parameters
    ----------
    folder
        The atlas's output folder (made if missing).
    grid
        The grid to measure: its settings must be the folder's (or ``force``).
    force
        Discard the cells of another grid's settings instead of refusing.

    Raises
    ------
    ParameterError
        If the folder holds cells measured with other settings and not ``force``.
    """

    def __init__(self, folder: Path, grid: AtlasGrid, force: bool = False):
        self.folder = Path(folder)
        self.cells = self.folder / _CELLS
        settings_file = self.folder / _SETTINGS
        if settings_file.exists():
            held = json.loads(settings_file.read_text())
            if held != grid.settings:
                if not force:
                    raise ParameterError(
                        f"{self.folder}: holds an atlas of other settings ({_describe(held)}; "
                        f"asked: {_describe(grid.settings)}): choose another --out, or --force "
                        "to measure it again"
                    )
                shutil.rmtree(self.cells, ignore_errors=True)
        self.cells.mkdir(parents=True, exist_ok=True)
        write_text_atomic(settings_file, json.dumps(grid.settings, indent=2))

    def rows(self, cell: SceneCell) -> list[dict]:
        """The rows measured so far in ``cell``'s scene (failed ones included)."""
        path = self.cells / f"{cell.key}.json"
        return json.loads(path.read_text()) if path.exists() else []

    def missing(self, cell: SceneCell, methods: tuple[str, ...]) -> list[str]:
        """The methods of ``methods`` not yet measured in ``cell``'s scene."""
        done = {row["method"] for row in self.rows(cell)}
        return [m for m in methods if m not in done]

    def add(self, cell: SceneCell, rows: list[dict]) -> None:
        """Add ``rows`` to the scene's file (atomically: an interrupt loses no cell)."""
        merged = {row["method"]: row for row in [*self.rows(cell), *rows]}
        write_text_atomic(self.cells / f"{cell.key}.json", json.dumps(list(merged.values())))

    def folder_of(self, cell: SceneCell) -> Path:
        """Where the scene's images go."""
        return self.cells / cell.key


def _describe(settings: dict) -> str:
    return ", ".join(f"{name} {settings.get(name)}" for name in sorted(settings))
