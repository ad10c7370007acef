"""The report's editions: one arm's run of the chapters per study file (:class:`Edition`,
:func:`editions`), and where the primary edition and the others publish and record.

Apart from :mod:`.report`, which runs them, so that the pages and the PDF (:mod:`.website`,
:mod:`.index`, :mod:`.citations`, :mod:`.paper`) can name them without importing the pipeline
that calls them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from ..infra.paths import shown_path

__all__ = ["Edition", "editions", "PRIMARY_STUDY", "RECORDINGS"]


PRIMARY_STUDY = "intelbot5"      # the dissertation's arm: its edition publishes into figures/
#: Where the chapters write their rerun recordings (their ``recordings_dir`` default); another
#: edition's go to ``RECORDINGS/<name>/``.
RECORDINGS = "build/recordings"


@dataclass(frozen=True)
class Edition:
    """One arm's run of the chapters: a study file and its robot file (as the reader names
    them). The primary edition runs every chapter with its default parameters and publishes
    into ``figures/``; another runs the chapters that take a ``robot_file`` or ``study_file``
    with its own and publishes into ``figures/<name>/``. A chapter that takes neither (04, on
    Jang's benchmarks) is the same for every arm and runs once; a chapter that takes
    ``study_files`` (08) compares the editions and runs once, after them."""

    name: str
    study_file: str
    robot_file: str
    primary: bool

    @property
    def subdir(self) -> str:
        return "" if self.primary else self.name

    def parameters(self, declared: Sequence[str]) -> dict | None:
        """The parameters of this edition's run of a chapter declaring ``declared``, or None
        when the chapter is not run for it."""
        if self.primary:
            return {}
        chosen = {k: v for k, v in (("robot_file", self.robot_file),
                                    ("study_file", self.study_file)) if k in declared}
        if chosen and "recordings_dir" in declared:   # its recordings beside, not over, the primary's
            chosen["recordings_dir"] = f"{RECORDINGS}/{self.name}"
        return chosen or None


def editions(params_dir: Path | None = None) -> list[Edition]:
    """One edition per study file ``params/studies/*.yaml``, the primary (intelbot5) first;
    a single primary edition with the chapters' defaults if there is no study file."""
    from ..study.study_files import load_study          # the study's robot file, validated
    from ..infra.paths import PARAMS

    files = sorted(((params_dir or PARAMS) / "studies").glob("*.yaml"))
    found = [Edition(f.stem, shown_path(f), load_study(f).robot_file, f.stem == PRIMARY_STUDY)
             for f in files]
    if not any(e.primary for e in found):
        return [Edition(PRIMARY_STUDY, "", "", True)]
    return sorted(found, key=lambda e: (not e.primary, e.name))
