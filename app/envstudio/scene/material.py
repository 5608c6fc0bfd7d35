"""Materials of reflectors and local objects (plain data)."""

from __future__ import annotations

from dataclasses import dataclass, field

from envstudio.scene.tangents import TangentField


@dataclass
class Material:
    """Diffuse + glossy material of seed 000 eq. 8.

    Attributes
    ----------
    kd : (3,) tuple of float
        Diffuse albedo k_d in [0, 1] per RGB channel (seed 000 eq. 2).
    fresnel : (3,) tuple of float
        f_λ, Schlick reflectance at normal incidence in [0, 1] per RGB channel (seed 000
        section 5.2: "the color of reflected white light at normal incidence").
    phong_exponent : float
        Phong lobe exponent N (seed 000 eq. 5–7).
    sharpness : float
        s ∈ [0, 1) of the Banks BRDF (seed 004 §5.3), for anisotropic methods.
    tangent_field : TangentField
        Where the anisotropic methods' tangents come from (scene/tangents.py).
    model : str or None
        The BRDF the ``reference`` integrates (``phong``, ``microfacet``, ``banks``)
        when the scene names one; None leaves the reference's own setting.
    """

    kd: tuple[float, float, float] = (0.0, 0.0, 0.0)
    fresnel: tuple[float, float, float] = (1.0, 1.0, 1.0)
    phong_exponent: float = 200.0
    sharpness: float = 0.9
    tangent_field: TangentField = field(default_factory=TangentField)
    model: str | None = None
    extra: dict[str, float] = field(default_factory=dict)
