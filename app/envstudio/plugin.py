"""The public API for environment-map methods, envmap-studio's own and other packages'.

A method is a :class:`Method` subclass that declares its :class:`Parameter` s and
draws the scene's reflectors each frame from :class:`FrameInputs`. A package
makes it appear in the viewer, ``--param``, ``bench``, ``compare`` and
``envstudio methods`` by naming it, or a :class:`Plugin` that bundles it with
its subcommands, figures, bakes and bench tables, as an entry point of the
group ``envstudio.methods``::

    [project.entry-points."envstudio.methods"]
    flat = "envstudio_flat:PLUGIN"

Shaders load by name through the method's ``self.programs.get("<folder>/<file>")``:
``Plugin.shaders`` adds the plugin's folder, whose files ``#include`` each
other and the shipped ``common/`` files by the same names. Time each pass with
``frame.timer.measure("label")``. The walk-through is ``docs/plugins.md``.

A method builds on this module and the public library, :data:`PUBLIC_LIBRARY`, and on
nothing else of envmap-studio: the engine, the measurements, the window, the commands and
the other methods are private. envmap-studio's methods are held to exactly that (the
import-linter contracts in its ``pyproject.toml`` and ``tests/test_public_library.py``) and
register the same way, one entry point each. A name this module exports is imported from
here; a GL-free bake (imported by a Dask worker without GL) takes what it needs from the
GL-free layers (``core``, ``io``, ``scene``) directly.
"""

from envstudio.core.images import tile, to_ldr, upright
from envstudio.core.parameters import Parameter, ParameterValues
from envstudio.core.presets import FRESNEL_PRESETS, fresnel_parameter, kd_parameter
from envstudio.engine.hooks import Bake, BenchTable, Command, Figure, FigureRequest, Plugin
from envstudio.engine.method import Method, ReportExtra, Session
from envstudio.errors import InputFileError, ParameterError, UserError
from envstudio.gpu.programs import ShaderCompileError, read_shader
from envstudio.gpu.timers import PassTimer
from envstudio.gpu.uniforms import set_uniform
from envstudio.io.images import write_image
from envstudio.measure.ground_truth import (
    MAX_TIME_LIMIT_S,
    ConvergenceStatus,
    GroundTruth,
    PairedEstimates,
    duration,
    is_checkpoint,
    project_convergence,
)
from envstudio.shading.eq8 import EQ8_PARAMETERS, set_eq8_uniforms
from envstudio.shading.gpu_scene import FrameInputs, GpuNode, GpuScene, StaticEnvironment
from envstudio.shading.miller_map import MillerDiffuseMap
from envstudio.shading.sh_irradiance import ShIrradiance, sh_parameters

PUBLIC_LIBRARY = (
    "envstudio.plugin",
    "envstudio.core",
    "envstudio.io",
    "envstudio.scene",
    "envstudio.gpu",
    "envstudio.envmap",
    "envstudio.prefilter",
    "envstudio.shading",
    "envstudio.errors",
    "envstudio.resources",
)
"""The modules a method may import (each with its submodules), besides its own package:
``core`` math, conventions and parameter declarations (no GL); ``io`` files and caches;
``scene`` the scene graph as plain data; ``gpu`` the context, shader loading, timers and
uniforms; ``envmap`` environment maps on the GPU; ``prefilter`` the prefilter library;
``shading`` the terms several techniques share and the scene on the GPU; ``errors`` the
user-facing exceptions; ``resources`` the shipped shaders and assets."""

__all__ = [
    "EQ8_PARAMETERS",
    "FRESNEL_PRESETS",
    "MAX_TIME_LIMIT_S",
    "PUBLIC_LIBRARY",
    "Bake",
    "BenchTable",
    "Command",
    "ConvergenceStatus",
    "Figure",
    "FigureRequest",
    "FrameInputs",
    "GpuNode",
    "GpuScene",
    "GroundTruth",
    "InputFileError",
    "Method",
    "MillerDiffuseMap",
    "PairedEstimates",
    "Parameter",
    "ParameterError",
    "ParameterValues",
    "PassTimer",
    "Plugin",
    "ReportExtra",
    "Session",
    "ShIrradiance",
    "ShaderCompileError",
    "StaticEnvironment",
    "UserError",
    "duration",
    "fresnel_parameter",
    "is_checkpoint",
    "kd_parameter",
    "project_convergence",
    "read_shader",
    "set_eq8_uniforms",
    "set_uniform",
    "sh_parameters",
    "tile",
    "to_ldr",
    "upright",
    "write_image",
]
