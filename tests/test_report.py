"""The report pipeline: publishing, failure reporting, index, manifest, reproducibility."""

from __future__ import annotations

import hashlib

import nbformat
import numpy as np
import pytest
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

from nfarm.paths import atomic_path
from nfarm.report import Table, build_report


def make_notebook(path, *code):
    cells = [new_markdown_cell(f"# Chapter {path.stem}"),
             new_code_cell('smoke = False\nseed = 0\nout_dir = "figures"',
                           metadata={"tags": ["parameters"]})]
    cells += [new_code_cell(c) for c in code]
    nbformat.write(new_notebook(cells=cells), path)


WRITE = """import matplotlib.pyplot as plt
from nfarm.plotting import save_figure
from nfarm.report import Table
fig, ax = plt.subplots()
ax.plot([0, 1], [0, 1])
save_figure(fig, out_dir, "{p}_line")
Table(["smoke"], [[smoke]]).save(out_dir, "{p}_params")"""


@pytest.fixture
def project(tmp_path):
    notebooks = tmp_path / "notebooks"
    notebooks.mkdir()
    make_notebook(notebooks / "01_first.ipynb", WRITE.format(p="01"))
    make_notebook(notebooks / "02_second.ipynb", WRITE.format(p="02"))
    dirs = dict(notebooks_dir=notebooks, figures_dir=tmp_path / "figures",
                build_dir=tmp_path / "build")
    return tmp_path, dirs


def digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.mark.notebook
def test_report_builds_index_and_manifest_and_is_reproducible(project):
    root, dirs = project
    stale = dirs["figures_dir"] / "01_removed_since.png"
    stale.parent.mkdir(parents=True)
    stale.write_bytes(b"old")
    assert build_report(smoke=True, **dirs) == 0
    figures = dirs["figures_dir"]
    assert not stale.exists(), "a chapter's old outputs are replaced by its new ones"
    assert (figures / "tables" / "01_params.csv").read_text() == "smoke\nTrue\n"
    manifest = (figures / "MANIFEST.sha256").read_text().splitlines()
    assert [line.split("  ")[1] for line in manifest] == [
        "01_line.png", "02_line.png", "tables/01_params.csv", "tables/01_params.md",
        "tables/02_params.csv", "tables/02_params.md"]
    for line in manifest:
        sha, name = line.split("  ")
        assert digest(figures / name) == sha
    index = (dirs["build_dir"] / "report" / "index.html").read_text()
    assert index.index("Chapter 01_first") < index.index("Chapter 02_second")
    assert "figures/01_line.png" in index and (dirs["build_dir"] / "report" / "01_first.html").exists()
    first = (figures / "MANIFEST.sha256").read_bytes()
    assert build_report(smoke=True, **dirs) == 0
    assert (figures / "MANIFEST.sha256").read_bytes() == first, "figures are byte-reproducible"


@pytest.mark.notebook
def test_a_failing_notebook_stops_the_run_and_names_the_cell(project, capsys):
    root, dirs = project
    make_notebook(dirs["notebooks_dir"] / "02_second.ipynb", "x = 1", "raise ValueError('bad joint')")
    assert build_report(smoke=True, **dirs) == 1
    err = capsys.readouterr().err
    assert "02_second.ipynb failed in cell 4" in err and "ValueError: bad joint" in err
    kept = dirs["build_dir"] / "notebooks" / "02_second.ipynb"
    assert f"kept at {kept}" in err and kept.exists()
    assert (dirs["figures_dir"] / "01_line.png").exists(), "earlier chapters are published"
    assert not (dirs["figures_dir"] / "MANIFEST.sha256").exists()


def test_table_formats_and_files(tmp_path):
    table = Table(["name", "value", "n"], [["a|b", -1e-17, np.int64(3)], ["c", 2.5, 4]],
                  floatfmt=["", ".3f", ""], caption="cap")
    assert table.to_csv() == "name,value,n\na|b,0.000,3\nc,2.500,4\n"
    assert table.to_markdown().splitlines()[2:] == [
        "| name | value | n |", "|---|---|---|", "| a\\|b | 0.000 | 3 |", "| c | 2.500 | 4 |"]
    table.save(tmp_path, "01_x")
    assert (tmp_path / "tables" / "01_x.csv").read_text() == table.to_csv()
    with pytest.raises(ValueError, match="table row 0 has 2 cells, expected 3"):
        Table(["a", "b", "c"], [[1, 2]])


def test_atomic_path_leaves_no_half_written_file(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("disk full")
    assert target.read_text() == "old"
    assert list(tmp_path.iterdir()) == [target]
