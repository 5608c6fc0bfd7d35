"""The atlas folder: its settings, one JSON file of rows per measured scene.

Everything read back goes through :mod:`.entries`: an unreadable or ill-shaped
settings file, ``cells`` folder or scene file is set aside with a note and what
it held is measured again (a settings file set aside takes the cells with it:
what they were measured with is unknown). A method is measured again when its
row failed (the reason is kept until then) or its images are missing.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from envstudio.errors import ParameterError
from envstudio.measure.atlas.entries import make_folder, read_json, set_aside, write_json
from envstudio.measure.atlas.grid import AtlasGrid, SceneCell

__all__ = ["AtlasStore"]

_SETTINGS = "atlas-settings.json"
_CELLS = "cells"
#: What a measured row holds besides the cell: numbers (or None) and image paths.
_NUMBERS = (
    "approximation_error",
    "scene_error",
    "scene_only_error",
    "approximation_psnr_db",
    "approximation_flip",
    "psnr_db",
    "flip",
    "ms_per_frame",
    "cost_ratio",
    "gpu_bytes",
)
_IMAGES = ("image", "heat_map", "reference_image")


class AtlasStore:
    """Rows of measured cells under ``folder/cells``, keyed by scene.

    Parameters
    ----------
    folder
        The atlas's output folder (it exists).
    grid
        The grid to measure: its settings must be the folder's (or ``force``).
    force
        Discard the cells of another grid's settings instead of refusing.

    Attributes
    ----------
    notes : list of str
        One line per entry set aside or measured again, in the order found.

    Raises
    ------
    ParameterError
        If the folder holds cells measured with other settings and not ``force``.
    """

    def __init__(self, folder: Path, grid: AtlasGrid, force: bool = False):
        self.folder = Path(folder)
        self.cells = self.folder / _CELLS
        self.notes: list[str] = []
        settings_file = self.folder / _SETTINGS
        held = read_json(settings_file, lambda value: isinstance(value, dict), self.notes)
        if self.notes and self.cells.exists():  # set aside: the cells' settings are unknown
            cells = set_aside(self.cells, "", [])
            self.notes[0] += f", with the cells measured under them (set aside as {cells.name})"
        if held is not None and held != grid.settings:
            if not force:
                raise ParameterError(
                    f"{self.folder}: holds an atlas of other settings ({_describe(held)}; "
                    f"asked: {_describe(grid.settings)}): choose another --out, or --force "
                    "to measure it again"
                )
            shutil.rmtree(self.cells, ignore_errors=True)
        make_folder(self.cells, self.notes)
        write_json(settings_file, grid.settings, indent=2)

    def rows(self, cell: SceneCell) -> list[dict]:
        """The rows measured so far in ``cell``'s scene (failed ones included)."""
        rows = read_json(self._file(cell), lambda value: _valid_rows(value, cell), self.notes)
        return rows or []

    def missing(self, cell: SceneCell, methods: tuple[str, ...]) -> list[str]:
        """The methods of ``methods`` to measure in ``cell``'s scene.

        Those with no row, a failed row, or a row whose images are missing (noted).
        """
        rows = {row["method"]: row for row in self.rows(cell)}
        todo = []
        for method in methods:
            row = rows.get(method)
            gone = [row[k] for k in _IMAGES if row and k in row]
            gone = [name for name in gone if not (self.cells / name).is_file()]
            if gone:
                self.notes.append(f"{self.cells / gone[0]}: missing; measured again")
            if row is None or row["error"] or gone:
                todo.append(method)
        return todo

    def add(self, cell: SceneCell, rows: list[dict]) -> None:
        """Add ``rows`` to the scene's file (atomically: an interrupt loses no cell)."""
        merged = {row["method"]: row for row in [*self.rows(cell), *rows]}
        write_json(self._file(cell), list(merged.values()))

    def folder_of(self, cell: SceneCell) -> Path:
        """Where the scene's images go (anything but a folder there is set aside)."""
        return make_folder(self.cells / cell.key, self.notes)

    def _file(self, cell: SceneCell) -> Path:
        return self.cells / f"{cell.key}.json"


def _valid_rows(value: object, cell: SceneCell) -> bool:
    """Whether ``value`` is a list of rows of ``cell``: failed, skipped or measured."""
    return isinstance(value, list) and all(_valid_row(row, cell) for row in value)


def _valid_row(row: object, cell: SceneCell) -> bool:
    if not isinstance(row, dict) or not isinstance(row.get("method"), str):
        return False
    if any(row.get(name) != value for name, value in cell.__dict__.items()):
        return False
    error, skipped = row.get("error", ""), row.get("skipped")
    if error is not None:
        return isinstance(error, str) and bool(error)
    if skipped is not None:
        return isinstance(skipped, str)
    numbers = all(_is_number(row.get(k, "")) for k in _NUMBERS)
    return numbers and all(isinstance(row.get(k), str) for k in _IMAGES)


def _is_number(value: object) -> bool:
    return value is None or (isinstance(value, (int, float)) and not isinstance(value, bool))


def _describe(settings: dict) -> str:
    return ", ".join(f"{name} {settings.get(name)}" for name in sorted(settings))
