"""Sphinx configuration of the alpes_dyn documentation.

Build: ``pip install ".[docs]" && sphinx-build -W -b html docs docs/_build/html``.
The parameter tables and the command outputs shown in the pages are generated at build time from
the shipped parameter file and the installed package (``docs/_ext/alpes_sphinx.py``), so they
cannot drift from the code.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

import alpes_dyn  # noqa: E402  (the installed package: docs describe what users get)

os.environ.setdefault("MPLBACKEND", "Agg")

project = "alpes_dyn"
author = "alpes_dyn developers"
copyright = "alpes_dyn developers"  # noqa: A001
release = alpes_dyn.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
    "alpes_sphinx",
]

exclude_patterns = ["_build", "README.md", "**/README.txt"]
templates_path: list[str] = []
html_static_path = ["_static"]
html_theme = "alabaster"
html_title = f"alpes_dyn {release}"
html_theme_options = {
    "description": "Dynamics, observability and state estimation of the Alpes Instruments robotic hand",
    "fixed_sidebar": True,
    "page_width": "1100px",
    "sidebar_width": "230px",
}
pygments_style = "sphinx"

# --- autodoc: members in source order, type hints rendered in the description (no extra package)
autodoc_default_options = {"members": True, "member-order": "bysource", "show-inheritance": True}
autodoc_typehints = "description"
autodoc_typehints_format = "short"
autoclass_content = "class"
python_use_unqualified_type_names = True

# --- napoleon: the package writes numpy-style sections
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_ivar = True          # "Attributes" as fields: no duplicate entries next to autodoc's members
napoleon_use_rtype = False
# A name that two classes both have as an attribute (StepParts.n and ChainParams.n; PathRatios.shape and
# RatioCurve.shape) met in a napoleon type such as "(n,) array" or "shape" is ambiguous to Sphinx's Python domain
# ("more than one target found"): such a word is prose, not a link, so those ambiguity warnings are not errors.
suppress_warnings = ["ref.python"]

# --- math: the report's equation numbers are written with \tag{...}
mathjax3_config = {"tex": {"tags": "none"}}

# --- sphinx-gallery: examples in docs/examples, generated pages in docs/auto_examples (not in git)
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "backreferences_dir": "gen_modules/backreferences",
    "doc_module": ("alpes_dyn",),
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "capture_repr": (),
    "show_memory": False,
    "show_signature": False,
}
