"""Seed 003's parameterized environment maps, offline half: the segmented ray tracer.

Seed 003 §3 ("System Overview") and §4 ("Layered EMs"), Figure 4: for each
sample of the parameter space (views), ray trace the scene and segment each
reflector part's image into diffuse, Fresnel, distant and local (colour +
alpha) layers, with the full composite as ground truth. views samples the
parameter space, trace does the tracing (Embree through embreex, no GL).
EM inference, the ``.pem`` file and the bake job are not built yet
(docs/pem/README.md).
"""

from envstudio.bake.pem.trace import TRACE_BOUNCES, SceneTracer, TracedView, trace_view
from envstudio.bake.pem.views import ViewSpace, arc_views, grid_views

__all__ = [
    "TRACE_BOUNCES",
    "SceneTracer",
    "TracedView",
    "ViewSpace",
    "arc_views",
    "grid_views",
    "trace_view",
]
