"""Setting uniforms from NumPy values without caring whether the compiler kept them."""

from __future__ import annotations

import moderngl
import numpy as np


def set_uniform(program: moderngl.Program, name: str, value) -> None:
    """Set uniform ``name`` if the program uses it.

    Matrices, (3, 3) or (4, 4), and arrays of them, (k, 3, 3) or (k, 4, 4), are
    NumPy arrays in the row-major maths convention and are transposed for GLSL's
    column-major storage; scalars, tuples and vectors are written as they are.
    Unused (optimised-out) uniforms are ignored.
    """
    if name not in program:
        return
    member = program[name]
    if isinstance(value, np.ndarray):
        array = np.asarray(value, dtype=np.float32)
        square = array.ndim in (2, 3) and array.shape[-2] == array.shape[-1]
        if square and array.shape[-1] in (3, 4):
            member.write(np.ascontiguousarray(np.swapaxes(array, -1, -2)).tobytes())
        else:
            member.write(np.ascontiguousarray(array).tobytes())
    elif isinstance(value, bool):
        member.value = int(value)
    else:
        member.value = value
