"""
A glossiness sweep
==================

The Phong exponent N of Kautz et al.'s hardware prefilter (``hwconv``, seed 004 §5.2): the
map is convolved on the GPU with the lobe ⟨r, l⟩^N, so a small N blurs the studio's lamps
into a soft sheen and a large one approaches the mirror.
"""

import numpy as np

import envstudio as es

scene = es.load_scene("studio")
exponents = [10, 50, 250, 1000]
frames = [es.render(scene, "hwconv", size=(64, 64), phong_exponent=n, border=64) for n in exponents]
print("left to right: N =", ", ".join(str(n) for n in exponents))
es.show(np.hstack([es.display(f) for f in frames]))
