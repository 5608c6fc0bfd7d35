"""Setting uniforms from NumPy values without caring whether the compiler kept them."""

from __future__ import annotations

import moderngl
import numpy as np


def set_uniform(program: moderngl.Program, name: str, value) -> None:
    """Set uniform ``name`` if the program uses it.

    Matrices are NumPy arrays in the row-major maths convention and are
    transposed for GLSL's column-major storage; scalars, tuples and vectors
    are written as they are. Unused (optimised-out) uniforms are ignored.
    """
    if name not in program:
        return
    member = program[name]
    if isinstance(value, np.ndarray):
        array = np.asarray(value, dtype=np.float32)
        if array.ndim == 2 and array.shape[0] == array.shape[1] and array.shape[0] in (3, 4):
            member.write(np.ascontiguousarray(array.T).tobytes())
        else:
            member.write(np.ascontiguousarray(array).tobytes())
    elif isinstance(value, bool):
        member.value = int(value)
    else:
        member.value = value
