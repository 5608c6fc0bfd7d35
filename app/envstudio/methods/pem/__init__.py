"""Method ``pem``: seed 003's parameterized environment maps, played back (issue 19).

blending maps the camera to the bake's parameter space and weighs the nearest
views, atlas packs every view's maps for the shader, gpu uploads them, verify
refuses a bake of another scene, method is the renderer (shaders/pem/).
"""

from envstudio.methods.pem.method import PemMethod, shipped_bake

__all__ = ["PemMethod", "shipped_bake"]
