"""Seed 003's parameterized environment maps, offline half: ray tracer and EM inference.

Seed 003 §3 ("System Overview") and §4: for each sample of the parameter space
(views), ray trace the scene and segment each reflector part's image into
diffuse, Fresnel, distant and local (colour + alpha) layers, with the full
composite as ground truth (Figure 4), then infer the environment maps whose
playback reproduces them. views samples the parameter space; trace does the
tracing (Embree through embreex, no GL); lookups computes the playback's
per-pixel EM lookups and the trilinear rendering matrix; mip the MIP chains;
infer the EM geometries and the solve of all MIP levels at once (§4, "EM
Inference", "EM MIPMAPs"); over the layered model refitted through its
composite (not in seed 003); hull the convex-hull split of the reflectors'
triangles; models the per-view models (layered distant + local RGBA, sphere at
infinity, static EM) and their predicted playback; pem_file the ``.pem`` file
(version 2: zstd half floats, levels as residuals); bake the resumable job of
one work unit per view on a process pool or Dask; numbers the issue's numbers
(studies/pem-bake/README.md).
"""

from envstudio.methods.pem.bake.bake import BakeReport, ViewTask, bake_view, run_bake
from envstudio.methods.pem.bake.hull import hull_mask, mesh_check, reflector_hulls
from envstudio.methods.pem.bake.infer import (
    BoxGeometry,
    EllipsoidGeometry,
    EMInference,
    MipInference,
    distant_box,
    em_origin,
    infer_distant,
    infer_em,
    infer_local_over,
    infer_mip,
    local_ellipsoid,
    min_volume_ellipsoid,
    rendering_matrix,
    solve_mip,
)
from envstudio.methods.pem.bake.lookups import (
    CHANNELS,
    LOD_BIAS,
    MODELS,
    PLAYBACK,
    PixelLookups,
    pixel_lookups,
    trilinear_matrix,
)
from envstudio.methods.pem.bake.models import (
    ViewModels,
    infer_view_models,
    playback_psnr,
    predict,
    static_em,
)
from envstudio.methods.pem.bake.pem_file import PemBake, load_pem, save_pem
from envstudio.methods.pem.bake.trace import TRACE_BOUNCES, SceneTracer, TracedView, trace_view
from envstudio.methods.pem.bake.views import ViewSpace, arc_views, grid_views

__all__ = [
    "CHANNELS",
    "LOD_BIAS",
    "MODELS",
    "PLAYBACK",
    "TRACE_BOUNCES",
    "BakeReport",
    "BoxGeometry",
    "EMInference",
    "EllipsoidGeometry",
    "MipInference",
    "PemBake",
    "PixelLookups",
    "SceneTracer",
    "TracedView",
    "ViewModels",
    "ViewSpace",
    "ViewTask",
    "arc_views",
    "bake_view",
    "distant_box",
    "em_origin",
    "grid_views",
    "hull_mask",
    "infer_distant",
    "infer_em",
    "infer_local_over",
    "infer_mip",
    "infer_view_models",
    "load_pem",
    "local_ellipsoid",
    "mesh_check",
    "min_volume_ellipsoid",
    "pixel_lookups",
    "playback_psnr",
    "predict",
    "reflector_hulls",
    "rendering_matrix",
    "run_bake",
    "save_pem",
    "solve_mip",
    "static_em",
    "trace_view",
    "trilinear_matrix",
]
