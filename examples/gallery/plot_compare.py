"""
Compare two methods against the reference
=========================================

``es.compare`` is ``envstudio compare`` in-process: each method is rendered at matched
parameters and measured against the reference of its reflectance model (PSNR, SSIM, FLIP
over the reflector's pixels, milliseconds per frame). The reference is accumulated until the
numbers are reliable, or the time limit. At 32×32 this takes a few seconds.
"""

import numpy as np

import envstudio as es

scene = es.load_scene("studio")
report = es.compare(scene, ["kautz", "hwconv"], size=(32, 32), time_limit=20)

# %%
# The table, one row per method (what ``compare.md`` holds):
for row in report.table:
    print(
        f"{row['method']:8s} PSNR {row['psnr_db']:5.1f} dB  SSIM {row['ssim']:.3f}  "
        f"FLIP {row['flip']:.3f}  {row['ms_per_frame']:.2f} ms  reliable: {row['reliable']}"
    )

# %%
# The frames as compared, left to right: kautz, hwconv, the reference.
frames = [report.images["kautz"], report.images["hwconv"], report.reference]
es.show(np.hstack([es.display(f) for f in frames]))
