"""
Error against the Phong exponent
================================

``es.error_curve`` measures each method against the exact reference of its reflectance model
(no tracing: what the environment map approximates) at each Phong exponent N, as
``envstudio compare --reference exact --param trace=false`` does at one. The mirror ignores N
altogether; ``hwconv`` convolves the map with the lobe ⟨r, l⟩^N itself and comes closest as N
grows. Plotted with matplotlib, at 32×32 and three exponents to stay fast.
"""

import matplotlib.pyplot as plt

import envstudio as es

scene = es.load_scene("studio")
curve = es.error_curve(
    scene, ["mirror", "kautz", "hwconv"], exponents=(10, 100, 1000), size=(32, 32)
)
for note in curve.get("notes", []):
    print(note)
for name, values in curve["methods"].items():
    errors = ", ".join(f"{e:.1%}" for e in values["median_relative_error"])
    print(f"{name:7s} median relative error at N = 10, 100, 1000: {errors}")

fig, ax = plt.subplots(figsize=(5, 3.5))
for name, values in curve["methods"].items():
    ax.plot(curve["exponents"], values["median_relative_error"], marker="o", label=name)
ax.set_xscale("log")
ax.set_xlabel("Phong exponent N")
ax.set_ylabel("median relative error")
ax.legend()
fig.tight_layout()
