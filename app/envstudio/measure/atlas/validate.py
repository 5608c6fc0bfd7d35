"""Check a whole atlas grid before its first cell: every cell's input loads and is in range."""

from __future__ import annotations

import OpenImageIO as oiio

from envstudio.errors import InputFileError, ParameterError
from envstudio.io.images import read_environment
from envstudio.measure.atlas.cells import resolve_env, resolve_mesh
from envstudio.measure.atlas.grid import AtlasGrid
from envstudio.measure.compare import method_classes, plan_parameters

__all__ = ["check_grid"]

#: Pixel types that hold display values, not radiance.
_INTEGER_PIXELS = (oiio.UINT8, oiio.INT8, oiio.UINT16, oiio.INT16)


def check_grid(grid: AtlasGrid) -> None:
    """Refuse, in one line, a grid some cell of which could not be measured.

    Writes nothing. Every method is known and takes the ``--param`` assignments and
    each (N, k_d) of the grid; every environment loads as linear HDR radiance (finite,
    2:1, not 8-bit); every mesh loads.

    Raises
    ------
    ParameterError
        An unknown method, environment or shape, or a value a method refuses.
    InputFileError
        An environment or mesh file that does not load.
    """
    classes = method_classes(list(grid.methods))
    plan_parameters(classes, grid.params)
    for n in grid.exponents:
        for kd in grid.kds:
            assignments = [f"phong_exponent={n!r}", f"kd={kd!r}"]
            try:
                plan_parameters(classes, [*grid.params, *assignments])
            except ParameterError as error:
                raise ParameterError(f"--exponents {n:g} --kd {kd:g}: {error}") from None
    for env in grid.envs:
        _check_environment(env)
    for mesh in grid.meshes:
        resolve_mesh(mesh)


def _check_environment(name: str) -> None:
    path = resolve_env(name)
    read_environment(path)
    image = oiio.ImageInput.open(str(path))
    pixels = image.spec().format.basetype
    image.close()
    if pixels in _INTEGER_PIXELS:
        raise InputFileError(
            f"--envs {name}: holds {oiio.TypeDesc(pixels)} pixels, display values; "
            "expected linear HDR radiance (float or half)"
        )
