"""Seed 000 eq. 8's shading as several methods share it: Schlick Fresnel over a diffuse term.

L_o = (1 − F) · k_d · L_diffuse(n) + F · L_glossy(r), F Schlick's of f_λ per RGB channel (seed 000
§5.2, eq. 8; seed 004 eq. 2); shaders/common/eq8.glsl evaluates it. ``mirror``,
``hwconv`` and ``banks`` declare :data:`EQ8_PARAMETERS` and set the uniforms with
:func:`set_eq8_uniforms`; L_diffuse = E(n)/π and L_glossy are their own.
"""

from __future__ import annotations

from envstudio.core.parameters import ParameterValues
from envstudio.core.presets import fresnel_parameter, kd_parameter
from envstudio.gpu.uniforms import set_uniform
from envstudio.shading.gpu_scene import FrameInputs

#: f_λ and k_d of eq. 8, linear RGB (a grey by default; f_λ takes core/presets.py's names).
EQ8_PARAMETERS = (
    fresnel_parameter(
        1.0, "Schlick reflectance at normal incidence, per RGB channel (1 = perfect mirror)."
    ),
    kd_parameter(0.0, "Diffuse albedo of the (1 − F) term, per RGB channel."),
)


def set_eq8_uniforms(program, frame: FrameInputs, values: ParameterValues) -> None:
    """The uniforms of common/eq8.glsl's shading: camera, f_λ and k_d (vec3).

    For every method that declares mirror's ``fresnel`` and ``kd``.
    """
    set_uniform(program, "u_camera_position", frame.camera_position)
    set_uniform(program, "u_fresnel", tuple(values["fresnel"]))
    set_uniform(program, "u_kd", tuple(values["kd"]))
