"""Method ``pem``: seed 003's parameterized environment maps, baked and played back.

bake/ is the offline half (ray tracer, EM inference, the ``.pem`` file; GL-free,
what a Dask worker imports); blending maps the camera to the bake's parameter
space and weighs the nearest views, atlas packs every view's maps for the
shader, gpu uploads them, verify refuses a bake of another scene, lookups_gl
gives the bake the playback shader's own lookups, method is the renderer
(shaders/pem/), offmanifold its measurements, commands ``envstudio bake pem``.
"""
