"""The works the study cites (``docs/references.bib``) and pandoc, which formats them: the index's
references list (:func:`references_html`) and the PDF's (:mod:`.paper`) are made from the same
file with the same citeproc style.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

from ..infra.notebook_runs import ReportError
from ..infra.paths import ROOT

__all__ = ["BIBLIOGRAPHY", "pandoc_path", "references_html"]


#: The works the study leans on (BibTeX): the PDF's references list and the index's are made from it.
BIBLIOGRAPHY = ROOT / "docs" / "references.bib"


def pandoc_path() -> str:
    """The pandoc binary the lock ships (the ``pypandoc-binary`` wheel's)."""
    import pypandoc

    return pypandoc.get_pandoc_path()


def references_html(bibliography: Path = BIBLIOGRAPHY) -> str:
    """Every work in ``bibliography`` as an HTML references list, formatted by pandoc's citeproc
    as the PDF's list is (its default style, Chicago author–date), sorted by author.

    Raises:
        ReportError: pandoc failed (one line with its message).
    """
    done = subprocess.run([pandoc_path(), "--from", "markdown", "--to", "html", "--citeproc",
                           "--bibliography", str(bibliography)],
                          input="---\nnocite: |\n  @*\n---\n", capture_output=True, text=True, timeout=120)
    if done.returncode != 0 or 'id="refs"' not in done.stdout:
        raise ReportError(f"the references list: pandoc failed: {' '.join(done.stderr.strip().splitlines()[-1:])}")
    return done.stdout
