"""The terms several techniques share, on the GPU, and the scene they draw.

Public library (DESIGN.md): any method, shipped or from another package, may build on it.

- :mod:`~envstudio.shading.gpu_scene`: the scene on the GPU (meshes, the environment's
  cube and lat-long, the static-EM capture, the dynamic cube) and a frame's inputs;
- :mod:`~envstudio.shading.eq8`: seed 000 eq. 8's combination (Fresnel, k_d, the
  diffuse and glossy terms) and its shared parameters;
- :mod:`~envstudio.shading.sh_irradiance`: the SH irradiance of seed 000 eq. 9 with cap
  lights, for the environment and the static EM;
- :mod:`~envstudio.shading.miller_map`: Miller's prefiltered diffuse map;
- :mod:`~envstudio.shading.materials`: the Banks material's declarations (shared by the
  Banks method and the reference);
- :mod:`~envstudio.shading.tangent_buffers`: per-vertex tangent fields on the GPU.

Their GLSL is in ``shaders/common/``.
"""
