"""Seed 003's parameterized environment maps, offline half: ray tracer and EM inference.

Seed 003 §3 ("System Overview") and §4 ("Layered EMs"), Figure 4: for each
sample of the parameter space (views), ray trace the scene and segment each
reflector part's image into diffuse, Fresnel, distant and local (colour +
alpha) layers, with the full composite as ground truth. views samples the
parameter space, trace does the tracing (Embree through embreex, no GL), and
infer (§4, "EM Inference") fits box / ellipsoid cube-map EMs to a layer
through the rendering matrix by conjugate gradient (finest MIP level only),
pem_file reads and writes the ``.pem`` file, and bake runs the bake as a
resumable job of one work unit per view. MIP levels and the local layer's
inference are not built yet (docs/pem/README.md).
"""

from envstudio.bake.pem.bake import BakeReport, ViewTask, bake_view, run_bake
from envstudio.bake.pem.infer import (
    BoxGeometry,
    EllipsoidGeometry,
    EMInference,
    distant_box,
    em_origin,
    infer_distant,
    infer_em,
    local_ellipsoid,
    min_volume_ellipsoid,
    rendering_matrix,
)
from envstudio.bake.pem.pem_file import PemBake, load_pem, save_pem
from envstudio.bake.pem.trace import TRACE_BOUNCES, SceneTracer, TracedView, trace_view
from envstudio.bake.pem.views import ViewSpace, arc_views, grid_views

__all__ = [
    "TRACE_BOUNCES",
    "BakeReport",
    "BoxGeometry",
    "EMInference",
    "EllipsoidGeometry",
    "PemBake",
    "SceneTracer",
    "TracedView",
    "ViewSpace",
    "ViewTask",
    "arc_views",
    "bake_view",
    "distant_box",
    "em_origin",
    "grid_views",
    "infer_distant",
    "infer_em",
    "load_pem",
    "local_ellipsoid",
    "min_volume_ellipsoid",
    "rendering_matrix",
    "run_bake",
    "save_pem",
    "trace_view",
]
