"""Seed 003's parameterized environment maps, offline half: ray tracer and EM inference.

Seed 003 §3 ("System Overview") and §4 ("Layered EMs"), Figure 4: for each
sample of the parameter space (views), ray trace the scene and segment each
reflector part's image into diffuse, Fresnel, distant and local (colour +
alpha) layers, with the full composite as ground truth. views samples the
parameter space, trace does the tracing (Embree through embreex, no GL), and
infer (§4, "EM Inference") fits box / ellipsoid cube-map EMs to a layer
through the rendering matrix by conjugate gradient (finest MIP level only).
MIP levels, the ``.pem`` file and the bake job are not built yet
(docs/pem/README.md).
"""

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
from envstudio.bake.pem.trace import TRACE_BOUNCES, SceneTracer, TracedView, trace_view
from envstudio.bake.pem.views import ViewSpace, arc_views, grid_views

__all__ = [
    "TRACE_BOUNCES",
    "BoxGeometry",
    "EMInference",
    "EllipsoidGeometry",
    "SceneTracer",
    "TracedView",
    "ViewSpace",
    "arc_views",
    "distant_box",
    "em_origin",
    "grid_views",
    "infer_distant",
    "infer_em",
    "local_ellipsoid",
    "min_volume_ellipsoid",
    "rendering_matrix",
    "trace_view",
]
