"""Matched parameters between methods: same material, comparable glossiness.

Methods that blur a mip chain by a LOD bias b (declaring ``lod_bias`` but not
``phong_exponent``) and methods with a Phong exponent N are matched through the
fitted mapping of prefilter/glossiness.py (seed 000 Figure 5 pairs N = 225 with
b = 2.25). Shared material parameters (f_λ, k_d) are copied as they are.
"""

from __future__ import annotations

import numpy as np

from envstudio.methods.base import Method
from envstudio.prefilter.glossiness import exponent_for_lod_bias, lod_bias_for_exponent

SHARED = ("fresnel", "kd", "phong_exponent", "lod_bias")


def _clamped(method: Method, name: str, value: float) -> float:
    declared = next(p for p in method.values if p.name == name)
    return float(np.clip(value, declared.minimum, declared.maximum))


def _hardware_lod_caveat(mip_method: Method) -> str:
    """What the match leaves out when b is a bias on the hardware's LOD (seed 000 §5.2).

    The fit relates N to the mip level b itself. Under ``lod_mode=bias`` the lookup reads
    level b plus the screen-space LOD, which curved reflectors make several levels large
    (docs/kautz: the studio bunny at 256² drops from 20.6 dB to 5.4 dB).
    """
    if "lod_mode" not in mip_method.values or mip_method.values["lod_mode"] != "bias":
        return ""
    return "; lod_mode=bias adds the screen-space LOD to b (lod_mode=level reads level b)"


def match_glossiness(target: Method, source: Method, cube_size: int) -> str | None:
    """Give ``target`` the look of ``source``: shared values copied, b ↔ N converted.

    Parameters
    ----------
    target
        The method whose values are set.
    source
        The method whose values are matched.
    cube_size
        Face edge n of the environment cube map, texels (b depends on it).

    Returns
    -------
    str or None
        One line saying how the glossiness was matched, or None when it was not converted.
    """
    for name in ("fresnel", "kd"):
        if name in source.values and name in target.values:
            target.values[name] = source.values[name]
    source_b = "lod_bias" in source.values and "phong_exponent" not in source.values
    target_b = "lod_bias" in target.values and "phong_exponent" not in target.values
    if source_b == target_b:
        for name in ("phong_exponent", "lod_bias"):
            if name in source.values and name in target.values:
                target.values[name] = source.values[name]
        return None
    if target_b and "phong_exponent" in source.values:
        exponent = float(source.values["phong_exponent"])
        fitted = float(lod_bias_for_exponent(exponent, cube_size))
        target.values["lod_bias"] = b = _clamped(target, "lod_bias", fitted)
        clamp = "" if b == fitted else f" (fit {fitted:.3f}, clamped)"
        line = f"b = {b:.3f} matched to N = {exponent:g} on a {cube_size}² cube{clamp}"
        return line + _hardware_lod_caveat(target)
    if source_b and "phong_exponent" in target.values:
        bias = float(source.values["lod_bias"])
        fitted = float(exponent_for_lod_bias(bias, cube_size))
        target.values["phong_exponent"] = n = _clamped(target, "phong_exponent", fitted)
        clamp = "" if n == fitted else f" (fit {fitted:.1f}, clamped)"
        line = f"N = {n:.1f} matched to b = {bias:g} on a {cube_size}² cube{clamp}"
        return line + _hardware_lod_caveat(source)
    return None
