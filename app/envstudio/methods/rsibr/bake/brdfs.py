"""The BRDFs baked into radiance sphere maps (seed 002 §2, §3, §5) and their parameters.

Each map texel holds seed 002 §2's lighting integral for the texel's normal n and
the map's view direction v,

    L_r(n, v) = ∫ f_r(l, v; n) L_i(l) cos θ_i dω_l,

written here as a sum of *lobes*: a lobe is a density s(l) with ∫ s dω = 1 that the
GPU samples and the CPU normalizes its quadrature by, times an attenuation
a(l) ∈ [0, 1] and an RGB colour c, so L_r = Σ c ∫ s(l) a(l) L_i(l) dω.

- ``phong`` (mirror warp, §3.3): the normalized Phong lobe about the mirror
  direction r, f_r cos θ_i = (N + 1)/2π max(r·l, 0)^N (seed 000 eq. 7, the kernel
  the other methods' prefilters use), a = 1. It depends on r alone, so under a
  constant environment L every texel is exactly L. Fresnel and the diffuse term
  are added when rendering (seed 000 eq. 8), as in ``mirror``.
- ``lambertian`` (normal warp, §3.3): s = max(n·l, 0)/π, albedo 1 (k_d is applied
  when rendering), so a constant environment gives L, and the map is irradiance/π.
- ``carpaint`` (mirror warp, §3, §5: "the clear polyurethane coat over a paint
  substrate"): a perfectly smooth clear coat reflecting F_c(n·v) of the mirror
  direction, over a base reached through the coat, (1 − F_c(n·v)) times the paint
  colour times a metallic Phong lobe of exponent N_b (weight ``metallic``) and a
  diffuse lobe (weight 1 − ``metallic``), each attenuated by (1 − F_c(n·l)) and cut
  at the horizon n·l > 0. F_c is Schlick's with the coat's f_λ. The coat is the
  only high-frequency lobe, which is why §3 warps such a BRDF as a mirror.
"""

from __future__ import annotations

from dataclasses import dataclass

from envstudio.core.parameters import Parameter
from envstudio.errors import ParameterError

__all__ = ["BRDFS", "Brdf", "brdf"]


@dataclass(frozen=True)
class Brdf:
    """A bakeable BRDF.

    Attributes
    ----------
    name : str
        ``phong``, ``lambertian`` or ``carpaint``.
    code : int
        Its number in shaders/rsibr/bake.glsl (``u_brdf``).
    warp : str
        The warp that matches its central direction (§3.3): ``mirror`` or ``normal``.
    parameters : tuple of Parameter
        What the bake depends on (ranges enforced on the command line).
    fresnel_in_map : bool
        The maps already hold Fresnel and the diffuse term (nothing is added when rendering).
    """

    name: str
    code: int
    warp: str
    parameters: tuple[Parameter, ...]
    fresnel_in_map: bool

    def values(self, given: dict[str, object] | None = None) -> dict[str, float]:
        """Every parameter's value: ``given`` validated, defaults for the rest.

        Raises
        ------
        ParameterError
            For a name this BRDF does not have or a value out of range.
        """
        given = dict(given or {})
        known = {p.name: p for p in self.parameters}
        unknown = sorted(set(given) - set(known))
        if unknown:
            have = ", ".join(known) or "none"
            raise ParameterError(
                f"unknown parameter {unknown[0]!r} for BRDF {self.name} (it has: {have})"
            )
        return {n: float(p.validate(given.get(n, p.default))) for n, p in known.items()}


_EXPONENT = Parameter(
    "phong_exponent", "float", 50.0, 1.0, 5000.0, "N", "Phong exponent of the lobe.", log=True
)
_PAINT = (
    Parameter("coat_f0", "float", 0.04, 0.0, 0.2, "f_λ", "Clear coat reflectance at normal."),
    Parameter(
        "base_exponent", "float", 40.0, 1.0, 1000.0, "N_b", "Metallic lobe exponent.", log=True
    ),
    Parameter("metallic", "float", 0.5, 0.0, 1.0, "", "Metallic lobe's share of the base."),
    Parameter("paint_red", "float", 0.55, 0.0, 1.0, "", "Base colour, red."),
    Parameter("paint_green", "float", 0.04, 0.0, 1.0, "", "Base colour, green."),
    Parameter("paint_blue", "float", 0.03, 0.0, 1.0, "", "Base colour, blue."),
)

#: The BRDFs by name.
BRDFS: dict[str, Brdf] = {
    b.name: b
    for b in (
        Brdf("phong", 0, "mirror", (_EXPONENT,), fresnel_in_map=False),
        Brdf("lambertian", 1, "normal", (), fresnel_in_map=False),
        Brdf("carpaint", 2, "mirror", _PAINT, fresnel_in_map=True),
    )
}


def brdf(name: str) -> Brdf:
    """The BRDF called ``name``; raises ParameterError naming the choices."""
    if name not in BRDFS:
        raise ParameterError(f"unknown BRDF {name!r} (expected one of {', '.join(BRDFS)})")
    return BRDFS[name]
