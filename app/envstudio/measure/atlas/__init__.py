"""``envstudio atlas``: every method × environment × shape × glossiness × k_d on one page.

A *cell* is one method on one environment, reflector shape, Phong exponent N,
diffuse weight k_d and camera. The cells of one scene (everything but the
method) are measured together by the fair ``compare`` (measure.compare: the
same pixel footprint, one reference per reflectance model, approximation and
scene errors apart), so a cell's numbers are exactly what ``compare`` gives on
that scene; the references are cached by content and shared between the
methods of one model. :mod:`.grid` names the cells, :mod:`.validate` checks them
all before the first is measured, :mod:`.cells` measures a scene's,
:mod:`.store` keeps them (resume, refuse another grid, measure again what is
corrupt or failed) through :mod:`.entries`, :mod:`.lock` keeps one atlas at a
time in a folder, :mod:`.pool` runs scenes in processes or on a Dask cluster,
and :mod:`.page` writes ``index.html``, ``atlas.json``, ``atlas.csv`` and ``atlas.png``.
"""
