"""Seed 002's radiance sphere maps, offline and GL-free: BRDFs (brdfs), CPU bake (cpu), file (bake).

The GPU bake is methods/rsibr/gpu_bake.py, beside the renderer.
"""
