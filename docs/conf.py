"""Sphinx configuration of the flexmvm documentation site.

Why Sphinx with MyST Markdown rather than MkDocs: the pages were already Markdown (MyST reads
them as they are, tables and math included), the CLI reference is generated from the click
commands by sphinx-click, and the API reference from the docstrings of the ``fm`` surface by
autodoc, all within one tool that numpy, scipy and scikit-fem use. ``-W`` makes every broken
link, reference or missing API entry an error (``.ci/run``).

Writing pages: a new page goes into a toctree of index.md (a page outside every toctree fails
``-W``; docs/notes/ is globbed, so a lab note needs nothing); link other pages and their
sections with relative Markdown links (``[text](page.md#section)``), and name repository files
outside docs/ as code (``src/flexmvm/...``): a Markdown link to them is a broken reference
in the built site.

The Python blocks of the pages are run by ``tests/test_docs_examples.py`` (as scripts, in a
subprocess), not again by this build: the build stays cheap, the test owns the time budget.

    python -m pip install -e ".[docs]"
    python -m sphinx -W --keep-going -b html docs out/docs
"""

from __future__ import annotations

import flexmvm

project = "flexmvm"
author = "the flexmvm authors"
copyright = "2026, the flexmvm authors"
release = flexmvm.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx_click",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "**/README.md"]

# MyST: $...$ and $$...$$ math, ::: fences for directives, anchors for ## and ### headings so
# pages can link to sections ([text](page.md#section)).
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
napoleon_google_docstring = True
napoleon_numpy_docstring = True
nitpicky = False

html_theme = "furo"
html_title = f"flexmvm {release}"
html_static_path: list[str] = []


def _check_api_reference(app) -> None:
    """Every name of ``flexmvm.__all__`` has its autodoc entry in api_reference.md: a name
    added to the ``fm`` surface without one is a warning, an error under ``-W``."""
    from sphinx.util import logging

    page = (app.srcdir / "api_reference.md").read_text(encoding="utf-8")
    missing = [n for n in flexmvm.__all__ if f":: flexmvm.{n}\n" not in page]
    if missing:
        logging.getLogger(__name__).warning(
            "api_reference.md: no entry for flexmvm.%s", ", flexmvm.".join(missing))


def _check_cli_reference(app) -> None:
    """Every sub-command of ``flexmvm`` has its sphinx-click entry in cli.md."""
    from sphinx.util import logging

    from flexmvm.cli import app as cli_app

    cli_app._register()  # the sub-commands are attached on first use (cli/app.py)
    page = (app.srcdir / "cli.md").read_text(encoding="utf-8")
    missing = [n for n in cli_app.cli.commands if f":prog: flexmvm {n}\n" not in page]
    if missing:
        logging.getLogger(__name__).warning("cli.md: no entry for flexmvm %s",
                                            ", flexmvm ".join(missing))


def setup(app):
    app.connect("builder-inited", _check_api_reference)
    app.connect("builder-inited", _check_cli_reference)
    return {"parallel_read_safe": True}
