"""Sphinx configuration of the envmap-studio site (``./run.sh docs``).

The gallery (``examples/gallery/*.py``) is executed at every build through the Python API on
a headless EGL context, and the viewer tour's screenshots are taken by the real window under
Xvfb; without either the build stops here with one line.
"""

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = Path(os.environ.get("ENVSTUDIO_CHECKOUT", HERE.parent))
os.environ.setdefault("ENVSTUDIO_CHECKOUT", str(ROOT))
sys.path.insert(0, str(HERE / "_ext"))

import envstudio_docs  # noqa: E402

import envstudio  # noqa: E402

envstudio_docs.check_context()
envstudio_docs.check_display()

project = "envmap-studio"
author = "the envmap-studio authors"
copyright = "envmap-studio authors, MIT licence"
release = envstudio.__version__
version = release

extensions = [
    "myst_nb",  # MyST Markdown pages (it sets up myst_parser) and docs/notebook.ipynb
    "sphinx.ext.autodoc",
    "numpydoc",
    "sphinxarg.ext",
    "sphinx_gallery.gen_gallery",
    "envstudio_docs",
]

source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "methods.md", "gallery/*.ipynb", "gallery/*.py", "**.zip"]
templates_path = []

myst_enable_extensions = ["colon_fence", "deflist"]
myst_heading_anchors = 3
# docs/notebook.ipynb is kept without outputs and shown as it is: tests/test_notebook.py runs it
# in a real kernel; running it here again would add about 20 s to every build
nb_execution_mode = "off"

html_theme = "furo"
html_title = f"envmap-studio {release}"
html_static_path = ["_static"]
html_show_sourcelink = False

autodoc_member_order = "bysource"
autodoc_typehints = "none"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

sphinx_gallery_conf = {
    "examples_dirs": [str(ROOT / "examples" / "gallery")],
    "gallery_dirs": ["gallery"],
    "filename_pattern": r"\.py$",
    "image_scrapers": ("envstudio_docs.scraper", "matplotlib"),
    "reset_modules": ("envstudio_docs.reset_shown",),
    "capture_repr": ("_repr_html_",),
    "download_all_examples": False,
    "show_memory": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "plot_gallery": "True",
    "run_stale_examples": True,  # every build shows what the code renders today
    "abort_on_example_error": True,
}
