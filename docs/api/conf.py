"""Sphinx configuration of the bhgrasp API reference (built with warnings as errors in CI)."""

project = "bhgrasp"
import shutil
from pathlib import Path

extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.mathjax", "myst_nb"]
napoleon_google_docstring = True
napoleon_numpy_docstring = False
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True}
nitpicky = False
exclude_patterns = ["_build"]
# The tutorials: notebooks/*.ipynb (committed without outputs) copied into tutorials/ and executed on every build
# in a temporary folder (they write files); an error or a timeout fails the build.
nb_execution_mode = "force"
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_in_temp = True
NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"
TUTORIALS = Path(__file__).resolve().parent / "tutorials"
html_theme = "alabaster"
suppress_warnings = ["ref.python"]  # numpy / pinocchio types in signatures have no inventory offline
napoleon_use_ivar = True  # dataclass "Attributes:" as fields, not a second description of each attribute


def _plain_text_math(app, what, name, obj, options, lines):
    """Docstrings write |x| for norms and absolute values; in reStructuredText that is a substitution."""
    lines[:] = [line.replace("|", "\\|") for line in lines]


def _copy_tutorials(app):
    """Fresh copies of the notebooks in tutorials/ (a build artefact, ignored by git)."""
    shutil.rmtree(TUTORIALS, ignore_errors=True)
    TUTORIALS.mkdir()
    for notebook in sorted(NOTEBOOKS.glob("*.ipynb")):
        shutil.copy(notebook, TUTORIALS / notebook.name)


def setup(app):
    app.connect("builder-inited", _copy_tutorials)
    app.connect("autodoc-process-docstring", _plain_text_math)
