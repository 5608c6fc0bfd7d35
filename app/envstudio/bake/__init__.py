"""Offline work, GL-free where it can be.

bake.rsibr: seed 002's radiance sphere maps; bake.pem: seed 003's segmented ray tracer.
"""
