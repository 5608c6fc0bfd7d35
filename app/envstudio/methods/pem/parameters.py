"""The ``pem`` method's parameters: the bake to play, the full orbit's cache, the EM
model and its layers, and the camera on the baked path."""

from __future__ import annotations

from envstudio.methods.pem.bake.orbit import ORBIT_BAKE, ORBIT_COUPLING, ORBIT_STEP
from envstudio.methods.pem.gpu import MODELS, TEXGENS
from envstudio.plugin import Parameter, fresnel_parameter, kd_parameter

__all__ = ["PEM_PARAMETERS"]

PEM_PARAMETERS = (
    Parameter(
        "pem",
        "path",
        "",
        help="The .pem bake to play; empty: the scene's shipped bake (assets/pem/<scene>.pem).",
        choices=(".pem",),
    ),
    Parameter(
        "coverage",
        "choice",
        "auto",
        help="orbit: every view the orbit camera reaches, baked on first use into the "
        "user cache (nearest the camera first; in the background in the window); file: "
        "the views of the .pem; auto: the orbit for a scene that ships a bake and no "
        "pem is named, else the file.",
        choices=("auto", "orbit", "file"),
    ),
    Parameter(
        "orbit_step",
        "choice",
        f"{ORBIT_STEP[0]:g}",
        help="Degrees between the full orbit's views in azimuth and elevation (each "
        "spacing its own cache; studies/pem-orbit/README.md: the finer, the closer midway, and the "
        "more views to bake).",
        choices=("20", "10", "5"),
    ),
    Parameter(
        "orbit_em_size",
        "choice",
        f"{ORBIT_BAKE['em_size']}",
        help="Cube face edge of the full orbit's maps (each size its own cache; "
        "studies/pem-orbit/README.md: 128 fits the teapot's self-reflections at grazing views, at "
        "four times the disk and the bake time).",
        choices=("64", "128"),
    ),
    Parameter(
        "orbit_fit",
        "choice",
        "refit",
        help="How the full orbit's layered maps are fitted (each its own cache): seed003, "
        "the paper's sequence (distant layer to its segment, then the local RGBA through "
        "the over); refit, then the distant and local colour refitted through the "
        "composite (not in the paper; studies/pem-orbit/README.md: the layered PEM then leads the "
        "sphere at grazing views).",
        choices=("refit", "seed003"),
    ),
    Parameter(
        "orbit_coupling",
        "choice",
        f"{ORBIT_COUPLING:g}",
        help="Coupling weight γ of the full orbit's views (each its own cache; not in the "
        "paper): 0, each view inferred alone; 0.1, each inferred again drawn towards its "
        "four neighbours' maps, which blend with less ghosting: the layered PEM then leads "
        "everywhere measured (studies/pem-orbit/README.md).",
        choices=("0", "0.1"),
    ),
    Parameter(
        "em_model",
        "choice",
        "layered",
        help="EM model: layered box + ellipsoid, one sphere at infinity, the static EM, or "
        "the PTM (surface textures, a polynomial in the view: seed 003 Figure 7).",
        choices=MODELS,
    ),
    Parameter(
        "texgen",
        "choice",
        "fragment",
        help="Reflection lookups per fragment, or per vertex as the paper (interpolated).",
        choices=TEXGENS,
        rebuild=True,
    ),
    Parameter(
        "lod_scale",
        "choice",
        "screen",
        help="MIP level from this image's pixel footprint (screen, as the hardware), or as "
        "the bake's resolution saw it (bake: the levels the solve fitted, at any size).",
        choices=("screen", "bake"),
    ),
    Parameter("blend", "bool", True, help="Blend the nearest 2 (arc) or 4 (grid) views."),
    Parameter("snap", "bool", False, help="Put the camera on the baked path at `path`."),
    Parameter("play", "bool", False, help="Move the camera along the path (snaps it)."),
    Parameter("path", "float", 0.5, 0.0, 1.0, "", "Position along the path's azimuths."),
    Parameter("path_elevation", "float", 0.5, 0.0, 1.0, "", "Position along a grid's elevations."),
    Parameter("play_speed", "float", 0.1, 0.01, 1.0, "1/s", "Path fraction per second."),
    Parameter("distant", "bool", True, help="Distant layer (the box map)."),
    Parameter("local", "bool", True, help="Local layer (the ellipsoid map, RGBA over)."),
    Parameter("fresnel_layer", "bool", True, help="Fresnel modulation of the reflection."),
    Parameter("diffuse", "bool", True, help="Diffuse layer (1 − F) k_d/π E_sh9(n)."),
    Parameter("hull", "bool", True, help="Convex-hull triangles use the distant map only."),
    fresnel_parameter(1.0, "Schlick f_λ of the Fresnel layer, per RGB channel."),
    kd_parameter(0.0, "Diffuse albedo of the diffuse layer, per RGB channel."),
)
