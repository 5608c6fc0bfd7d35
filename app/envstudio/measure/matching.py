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
16.4 dB at b = 0, the mirror (studies/kautz-border-and-sun). The reverse match, N from a mip
method's b, takes b as a level too; it leaves that method's ``lod_mode`` as it
is and says so in its line when that is ``bias``.

Every value a match sets, converted or copied, is clamped to the range the target
declares (:func:`assign_clamped`): a fitted or copied value beyond it (kautz's
default b = 1.7 on a 256² cube is N ≈ 8651, above rsibr's 5000) is set to the
nearest end, and the match line says so ("N = 5000 (clamped from 8651)"), never
a :class:`ParameterError`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from envstudio.core.ggx import alpha_for_exponent, exponent_for_alpha
from envstudio.core.parameters import Parameter
from envstudio.engine.method import Method
from envstudio.errors import ParameterError
from envstudio.prefilter.glossiness import exponent_for_lod_bias, lod_bias_for_exponent

SHARED = ("fresnel", "kd", "phong_exponent", "lod_bias", "roughness")
MATCH_LOD_MODE = "level"
"""The ``lod_mode`` a mip method is matched at: b is then the level the fit relates to N."""
GLOSSY = ("phong_exponent", "lod_bias", "roughness")
"""The glossiness parameters a match converts or copies."""
SYMBOLS = {"phong_exponent": "N", "lod_bias": "b", "roughness": "alpha"}
"""How a match line names a parameter."""


def _clamp(declared: Parameter, value: object) -> tuple[object, bool]:
    """``value`` moved into ``declared``'s range, and whether it was outside: a number to the
    nearest end, each of a colour's components; anything else as it is."""
    low = -math.inf if declared.minimum is None else declared.minimum
    high = math.inf if declared.maximum is None else declared.maximum
    if declared.kind == "color" and isinstance(value, (tuple, list)):
        inside = tuple(min(max(float(c), low), high) for c in value)
        return inside, inside != tuple(float(c) for c in value)
    if declared.kind in ("float", "int") and isinstance(value, (int, float)):
        inside = min(max(value, low), high)
        return (round(inside) if declared.kind == "int" else inside), inside != value
    return value, False


def assign_clamped(target: Method, name: str, value: object) -> str:
    """Set ``target``'s ``name`` to ``value``, clamped to the range ``target`` declares.

    Parameters
    ----------
    target
        The method whose value is set; it declares ``name``.
    name
        The parameter.
    value
        The matched value: converted from another method's, or copied from it.

    Returns
    -------
    str
        Empty when ``target`` took ``value`` as it is; else what happened, to add to a match
        line: ``" (clamped from 8651)"``, or, for a choice ``target`` lacks or a value it
        cannot take at all (NaN), ``" (kept: no lod_mode=bias)"`` with its value left as it was.
    """
    declared = next(p for p in target.values if p.name == name)
    inside, clamped = _clamp(declared, value)
    try:
        target.values[name] = inside
    except ParameterError:  # a choice it lacks, NaN
        return f" (kept: no {name}={value})"
    if not clamped:
        return ""
    if declared.kind == "color":
        return f" (clamped from {', '.join(f'{c:.4g}' for c in value)})"
    return f" (clamped from {value:.4g})"


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
    if assign_clamped(mip_method, "lod_mode", MATCH_LOD_MODE):
        return f", at lod_mode={before}: it has no lod_mode={MATCH_LOD_MODE}"
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
        One line saying how the glossiness was matched and what was clamped, or None when
        nothing was converted or clamped (values copied as they are).
    """
    material = _copy(target, source, ("fresnel", "kd"))
    line = match_roughness(target, source)
    if line is not None:
        return _joined(line, material)
    source_b = "lod_bias" in source.values and "phong_exponent" not in source.values
    target_b = "lod_bias" in target.values and "phong_exponent" not in target.values
    if source_b == target_b:
        return _joined(
            None, material + _copy(target, source, ("phong_exponent", "lod_bias", "lod_mode"))
        )
    if target_b and "phong_exponent" in source.values:
        exponent = float(source.values["phong_exponent"])
        clamp = assign_clamped(
            target, "lod_bias", float(lod_bias_for_exponent(exponent, cube_size))
        )
        b = target.values["lod_bias"]
        line = f"b = {b:.3f}{clamp} matched to N = {exponent:g} on a {cube_size}² cube"
        return _joined(line + _match_at_level(target), material)
    if source_b and "phong_exponent" in target.values:
        bias = float(source.values["lod_bias"])
        fitted = float(exponent_for_lod_bias(bias, cube_size))
        clamp = assign_clamped(target, "phong_exponent", fitted)
        n = target.values["phong_exponent"]
        line = f"N = {n:.5g}{clamp} matched to b = {bias:g} on a {cube_size}² cube"
        return _joined(line + _hardware_lod_caveat(source), material)
    return _joined(None, material)


def _copy(target: Method, source: Method, names: Sequence[str]) -> list[str]:
    """Copy ``names`` that both declare from ``source`` to ``target``, each clamped to
    ``target``'s range (:func:`assign_clamped`); what was clamped or kept, one item each
    (``"N = 5000 (clamped from 8651) copied from reference"``)."""
    notes = []
    for name in names:
        if name in source.values and name in target.values:
            note = assign_clamped(target, name, source.values[name])
            if note:
                shown = target.values[name]
                value = f"{shown:.5g}" if isinstance(shown, float) else str(shown)
                notes.append(f"{SYMBOLS.get(name, name)} = {value}{note} copied from {source.name}")
    return notes


def _joined(line: str | None, notes: list[str]) -> str | None:
    """A match line with the copies' notes after it (None: neither)."""
    parts = ([line] if line is not None else []) + notes
    return "; ".join(parts) if parts else None


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
        clamp = assign_clamped(target, "roughness", float(alpha_for_exponent(exponent)))
        alpha = target.values["roughness"]
        return f"alpha = {alpha:.4g}{clamp} matched to N = {exponent:g} {ALPHA_OF_N}"
    if source_alpha and not target_alpha and "phong_exponent" in target.values:
        alpha = float(source.values["roughness"])
        clamp = assign_clamped(target, "phong_exponent", float(exponent_for_alpha(alpha)))
        n = target.values["phong_exponent"]
        return f"N = {n:.5g}{clamp} matched to alpha = {alpha:g} {ALPHA_OF_N}"
    return None


ALPHA_OF_N = "(alpha = sqrt(2 / (4N + 2)))"


def match_through(
    targets: Sequence[Method], source: Method, hub: Method | None, cube_size: int
) -> dict[str, str | None]:
    """Match every one of ``targets`` to ``source`` through ``hub``'s Phong exponent.

    ``compare`` and the atlas hold one Phong exponent N (the reference's) and match
    each method to it (:func:`match_glossiness`). The viewer's grid and split screen
    do the same: ``hub`` (the ground truth) first takes ``source``'s look (its N from
    ``source``'s b, α or N; f_λ and k_d copied), then each target is matched to the hub
    exactly as ``compare`` matches a method to the reference. Matching two methods
    directly would miss the pairs with no direct conversion (a LOD bias and a GGX α).

    Parameters
    ----------
    targets
        The methods whose values are set (``source`` among them is skipped).
    source
        The method whose look the others take.
    hub
        A method with a ``phong_exponent`` (the ground truth); None: direct matching.
    cube_size
        Face edge n of the environment cube map, texels.

    Returns
    -------
    dict of str to str or None
        Each matched target's name → its match line (:func:`match_glossiness`). A target
        with a glossiness parameter matched through ``hub`` has the hub's line too (what
        its N came from): alone where it took the hub's N as it is, else after its own
        (``"N = 5000 (clamped from 8651) copied from reference; reference: N = 8650.8
        matched to b = 1.7 on a 256² cube"``).
    """
    lines: dict[str, str | None] = {}
    hub_line = None
    if hub is not None and source is not hub:
        lines[hub.name] = hub_line = match_glossiness(hub, source, cube_size)
    via = hub if hub is not None else source
    for target in targets:
        if target is not source and target is not via:
            line = match_glossiness(target, via, cube_size)
            glossy = any(name in target.values for name in GLOSSY)
            if hub_line is not None and glossy:  # what the hub's N, matched or copied, came from
                line = hub_line if line is None else f"{line}; {via.name}: {hub_line}"
            lines[target.name] = line
    return {target.name: lines[target.name] for target in targets if target.name in lines}


GLOSSINESS_NAMES = (*SHARED, "lod_mode")
"""The values :func:`match_glossiness` reads and sets."""


def glossiness(method: Method) -> tuple:
    """``method``'s values of :data:`GLOSSINESS_NAMES` that it declares, comparable with ==."""
    return tuple((name, method.values[name]) for name in GLOSSINESS_NAMES if name in method.values)


class GlossinessLink:
    """Keeps a set of methods matched: when one's glossiness or material changes, the others
    follow (:func:`match_through`); unchanged methods are left alone between changes.

    Each call compares every method's :func:`glossiness` with what it was after the
    last call. The source is the main method when it changed or is new (the first
    call, matching switched on again), else the first method that changed; a method
    that is only new (a tile just added) takes the look, it does not give it.
    """

    def __init__(self) -> None:
        self._seen: dict[str, tuple] = {}
        self.lines: dict[str, str | None] = {}
        """The last match's lines, by target name."""

    def forget(self) -> None:
        """Match everything to the main method on the next :meth:`follow` (matching re-enabled)."""
        self._seen.clear()

    def follow(
        self, methods: Sequence[Method], main: Method, hub: Method | None, cube_size: int
    ) -> Method | None:
        """Match ``methods`` (``main`` among them or not) to the one that changed.

        Returns
        -------
        Method or None
            The source the others were matched to; None when nothing changed.
        """
        members = list({id(m): m for m in [main, *methods]}.values())
        changed = [
            m for m in members if m.name in self._seen and self._seen[m.name] != glossiness(m)
        ]
        new = [m for m in members if m.name not in self._seen]
        source = None
        if main in changed or main in new or (new and not changed):
            source = main
        elif changed:
            source = changed[0]
        if source is not None:
            self.lines = match_through(members, source, hub, cube_size)
        self._seen = {m.name: glossiness(m) for m in members}
        return source
