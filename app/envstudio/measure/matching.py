"""Matched parameters between methods: same material, comparable glossiness.

Methods that blur a mip chain by a LOD bias b (declaring ``lod_bias`` but not
``phong_exponent``) and methods with a Phong exponent N are matched through the
fitted mapping of prefilter/glossiness.py (seed 000 Figure 5 pairs N = 225 with
b = 2.25). Shared material parameters (f_λ, k_d) are copied as they are.

A method with a GGX ``roughness`` α (``splitsum``) and one with a Phong exponent N
(the reference, whose ``model=microfacet`` renders α = √(2 / (4N + 2)), core.ggx) are
matched through that same mapping, both ways (:func:`match_roughness`).

The fit relates N to the mip level b itself. A mip method that declares
``lod_mode`` is therefore matched at ``lod_mode=level``. Under the paper's
``lod_mode=bias`` the lookup reads level b plus the hardware's screen-space LOD,
and no constant b makes up for that. On the studio bunny at 256² that LOD spans
2.1–5.7 levels over the reflector (10th–90th percentile, textureQueryLod). The
matched b at level mode gives 19.8 dB against the reference. Bias mode gives
5.6 dB at the matched b, 15.3 dB with b corrected by the median LOD, and at most
16.4 dB at b = 0, the mirror (docs/kautz). The reverse match, N from a mip
method's b, takes b as a level too; it leaves that method's ``lod_mode`` as it
is and says so in its line when that is ``bias``.
"""

from __future__ import annotations

import numpy as np

from envstudio.core.ggx import alpha_for_exponent, exponent_for_alpha
from envstudio.engine.method import Method
from envstudio.prefilter.glossiness import exponent_for_lod_bias, lod_bias_for_exponent

SHARED = ("fresnel", "kd", "phong_exponent", "lod_bias", "roughness")
MATCH_LOD_MODE = "level"
"""The ``lod_mode`` a mip method is matched at: b is then the level the fit relates to N."""


def _clamped(method: Method, name: str, value: float) -> float:
    declared = next(p for p in method.values if p.name == name)
    return float(np.clip(value, declared.minimum, declared.maximum))


def _match_at_level(mip_method: Method) -> str:
    """Set ``lod_mode=level`` where ``mip_method`` declares it; what the match line adds.

    Parameters
    ----------
    mip_method
        The method whose ``lod_bias`` was just matched to N.

    Returns
    -------
    str
        The text added to the match line: empty when the method has no ``lod_mode``.
    """
    if "lod_mode" not in mip_method.values:
        return ""
    before = mip_method.values["lod_mode"]
    mip_method.values["lod_mode"] = MATCH_LOD_MODE
    if before == MATCH_LOD_MODE:
        return f", matched at lod_mode={MATCH_LOD_MODE}"
    return (
        f", matched at lod_mode={MATCH_LOD_MODE}, not {before}: {before} adds the screen-space "
        "LOD to b"
    )


def _hardware_lod_caveat(mip_method: Method) -> str:
    """What a match toward N leaves out when the source's b is a bias (seed 000 §5.2).

    Parameters
    ----------
    mip_method
        The method whose ``lod_bias`` the exponent was matched to.

    Returns
    -------
    str
        Empty unless ``mip_method`` is at ``lod_mode=bias``: its lookup then reads
        level b plus the screen-space LOD, which curved reflectors make several
        levels large, so it looks blurrier than the matched N.
    """
    if "lod_mode" not in mip_method.values or mip_method.values["lod_mode"] != "bias":
        return ""
    return "; lod_mode=bias adds the screen-space LOD to b (lod_mode=level reads level b)"


def match_glossiness(target: Method, source: Method, cube_size: int) -> str | None:
    """Give ``target`` the look of ``source``: shared values copied, b ↔ N converted.

    A mip method matched to N is put at ``lod_mode=level`` when it declares
    ``lod_mode`` (see the module's docstring for why).

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
    line = match_roughness(target, source)
    if line is not None:
        return line
    source_b = "lod_bias" in source.values and "phong_exponent" not in source.values
    target_b = "lod_bias" in target.values and "phong_exponent" not in target.values
    if source_b == target_b:
        for name in ("phong_exponent", "lod_bias", "lod_mode"):
            if name in source.values and name in target.values:
                target.values[name] = source.values[name]
        return None
    if target_b and "phong_exponent" in source.values:
        exponent = float(source.values["phong_exponent"])
        fitted = float(lod_bias_for_exponent(exponent, cube_size))
        target.values["lod_bias"] = b = _clamped(target, "lod_bias", fitted)
        clamp = "" if b == fitted else f" (fit {fitted:.3f}, clamped)"
        line = f"b = {b:.3f} matched to N = {exponent:g} on a {cube_size}² cube{clamp}"
        return line + _match_at_level(target)
    if source_b and "phong_exponent" in target.values:
        bias = float(source.values["lod_bias"])
        fitted = float(exponent_for_lod_bias(bias, cube_size))
        target.values["phong_exponent"] = n = _clamped(target, "phong_exponent", fitted)
        clamp = "" if n == fitted else f" (fit {fitted:.1f}, clamped)"
        line = f"N = {n:.1f} matched to b = {bias:g} on a {cube_size}² cube{clamp}"
        return line + _hardware_lod_caveat(source)
    return None


def match_roughness(target: Method, source: Method) -> str | None:
    """GGX α ↔ Phong N by the reference's α = √(2 / (4N + 2)) (core.ggx), either way.

    Parameters
    ----------
    target
        The method whose ``roughness`` or ``phong_exponent`` is set.
    source
        The method it is matched to; exactly one of the two declares ``roughness``.

    Returns
    -------
    str or None
        One line saying how it was matched, or None when neither way applies.
    """
    target_alpha, source_alpha = "roughness" in target.values, "roughness" in source.values
    if target_alpha and not source_alpha and "phong_exponent" in source.values:
        exponent = float(source.values["phong_exponent"])
        target.values["roughness"] = alpha = _clamped(
            target, "roughness", alpha_for_exponent(exponent)
        )
        return f"alpha = {alpha:.4g} matched to N = {exponent:g} (alpha = sqrt(2 / (4N + 2)))"
    if source_alpha and not target_alpha and "phong_exponent" in target.values:
        alpha = float(source.values["roughness"])
        fitted = exponent_for_alpha(alpha)
        target.values["phong_exponent"] = n = _clamped(target, "phong_exponent", fitted)
        clamp = "" if n == fitted else f" (exactly {fitted:.4g}, clamped)"
        return f"N = {n:.4g} matched to alpha = {alpha:g}{clamp} (alpha = sqrt(2 / (4N + 2)))"
    return None
