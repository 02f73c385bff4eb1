"""Sphinx configuration of the bhgrasp API reference (built with warnings as errors in CI)."""

project = "bhgrasp"
extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.mathjax"]
napoleon_google_docstring = True
napoleon_numpy_docstring = False
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True}
nitpicky = False
exclude_patterns = ["_build"]
html_theme = "alabaster"
suppress_warnings = ["ref.python"]  # numpy / pinocchio types in signatures have no inventory offline
napoleon_use_ivar = True  # dataclass "Attributes:" as fields, not a second description of each attribute


def _plain_text_math(app, what, name, obj, options, lines):
    """Docstrings write |x| for norms and absolute values; in reStructuredText that is a substitution."""
    lines[:] = [line.replace("|", "\\|") for line in lines]


def setup(app):
    app.connect("autodoc-process-docstring", _plain_text_math)
