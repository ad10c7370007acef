"""Every chapter notebook: committed clean, thin parameters, and runs headlessly in smoke mode."""

from __future__ import annotations

import ast
import json
import re

import papermill
import pytest

from nfarm.infra.paths import FIGURES, NOTEBOOKS, ROOT
from nfarm.infra.notebook_runs import chapters, run_notebook
from nfarm.publishing.pages import COURSE_TAGS, chapter_title, export_html, numbered_outputs

NOTEBOOK_FILES = chapters(NOTEBOOKS)


def run_chapter(notebook, output, parameters):
    """Run a chapter as ``make report`` does: without the course's exercises (their cells are
    tested in test_course.py)."""
    run_notebook(notebook, output, parameters, remove_tags=COURSE_TAGS)


REQUIRED_PARAMETERS = {"seed", "smoke", "out_dir"}


#: Tables of every row saved for machines (nfarm.study.summary.long_table); their pages show reading copies.
LONG_TABLES = {"07_summary", "08_learned"}

#: What a page's prose (its markdown, code and tables left out) must not hold, each a kind and a pattern.
PROSE_DEFECTS = (("a zero-padded chapter number", r"\b(?:[Cc]hapters?|[Ss]ections?|[Ff]igures?|[Tt]ables?)\s+0\d"),
                 ("a file stem", r"\b0\d_[a-z]\w+"),
                 ("a build log", r"\bran in this run\b|\bfiles? made and\b|\bwere read from\b"),
                 ("a number that is not finite", r"(?<![\w-])-?(?:inf|nan)(?!\w)"),     # as Python prints one
                 # a value below 1e-7 of its unit (1e-9 of a whole, in %) printed with digits: rounding or a
                 # solver's tolerance, not data (shown as "< 1e-8 N·m", nfarm.presentation.tables.shown)
                 ("a value at noise level printed with digits",
                  r"(?<![\w.])\d\.\d+e-(?:0[5-9]|[1-9]\d)\s?%|(?<![\w.])\d\.\d+e-(?:0[89]|[1-9]\d)\s?(?:N·m|mm\b|m\b|rad\b|°|deg\b)"))


def prose_defect(words: str) -> tuple[str, str] | None:
    """The first of :data:`PROSE_DEFECTS` in ``words``: its kind and the text around it."""
    for kind, pattern in PROSE_DEFECTS:
        found = re.search(f".{{0,50}}(?:{pattern}).{{0,30}}", words)
        if found:
            return kind, found.group(0)
    return None


@pytest.mark.parametrize("words, kind", [
    ("as chapter 06 shows", "a zero-padded chapter number"),
    ("its credit, in 07_ik_credit, says", "a file stem"),
    ("0 files made and 9 reused", "a build log"),
    ("LM needs -inf% fewer iterations", "a number that is not finite"),
    ("an error of nan mm", "a number that is not finite"),
    ("ridge: < 1e-6 % and 8.09e-09 N·m on the worst joint", "a value at noise level printed with digits"),
    ("τ5 NRMSE 4.976e-06 %", "a value at noise level printed with digits"),
    ("LM ends 8.8e-10 m from the target", "a value at noise level printed with digits"),
    ("the spacing of doubles near 1 is 2.2e-16); < 1e-8 N·m; a step of 2.5e-3 m; 1.2e-4 rad", None),
    ("LM ends 5.9e-06 m from the target; σ_min is 8.43e-06 m; at most 3.8e-05 mm and 5.4e-07° away", None),
    ("as chapter 6 shows, 0.9 mm in Figure 6.2; an infinite line; nanometres; no exception, no NaN", None)])
def test_the_prose_check_fails_on_each_defect(words, kind):
    found = prose_defect(words)
    assert (found[0] if found else None) == kind


def check_page(notebook, executed, where):
    """The chapter's page as the report writes it reads as a page for a reader: a title, every
    figure captioned (visibly and as alternative text), no path of the machine, no "1 times",
    no prose number with more digits than a measurement supports, one parameters cell."""
    page = where / f"{notebook.stem}.html"
    export_html(executed, page, title=chapter_title(notebook))
    text = page.read_text(encoding="utf-8")
    assert "<title>Notebook</title>" not in text and f"<title>{chapter_title(notebook)}" in text
    images = re.findall(r"<img\b[^>]*>", text)
    assert images, "the page shows its figures"
    for image in images:
        alt = re.search(r'\balt="([^"]*)"', image)
        assert alt and alt.group(1).strip() and "No description" not in alt.group(1), \
            f"a figure without a caption: {image[:120]}"
    assert text.count("<figcaption") >= text.count('class="nfarm-figure"') > 0
    # Figures are numbered by chapter in the order a reader first meets them: 6.1, 6.2, …
    numbers = re.findall(r"<figcaption[^>]*><b>Figure (\d+)\.(\d+)\.</b>", text)
    assert len(numbers) == text.count("<figcaption"), "every caption carries its figure's number"
    assert {int(c) for c, _ in numbers} == {int(notebook.stem[:2])}, numbers
    first = list(dict.fromkeys(int(k) for _, k in numbers))
    assert first == list(range(1, len(first) + 1)), f"figures numbered out of order: {first}"
    assert str(ROOT) not in text, "a path of the checkout on the page"   # (the tests' own paths are parameters)
    prose = " ".join(re.sub(r"<[^>]+>", " ", m) for m in re.findall(
        r'<div class="jp-RenderedHTMLCommon jp-RenderedMarkdown[^"]*"[^>]*>(.*?)</div>', text, flags=re.S))
    assert not re.search(r"(?<![\d.,])[01] times\b", prose), re.search(r".{60}(?<![\d.,])[01] times\b.{20}", prose)
    # Prose for a reader (the markdown, without its code and tables): chapters and sections by their plain numbers,
    # no file stem where a figure or table is meant, no log of the build that made the page
    words = " ".join(re.sub(r"<[^>]+>", " ", re.sub(r"<code>.*?</code>|<table.*?</table>", " ", m, flags=re.S))
                     for m in re.findall(r'<div class="jp-RenderedHTMLCommon jp-RenderedMarkdown[^"]*"[^>]*>(.*?)</div>',
                                         text, flags=re.S))
    found = prose_defect(words)
    assert not found, f"{found[0]} in the prose: {found[1]!r}"
    for number in re.findall(r"(?<![\w.,])\d[\d,]*\.\d+|(?<![\w.,])\d{1,3}(?:,\d{3}){2,}", prose):
        digits = number.replace(",", "").replace(".", "").lstrip("0").rstrip("0" if "." not in number else "")
        assert len(digits) <= (5 if "." in number else 6), f"false precision in prose: {number}"
    assert text.count("# Parameters") <= 1, "the parameters show once"


def test_there_are_chapters():
    assert [nb.name for nb in NOTEBOOK_FILES][:1] == ["01_dh_model.ipynb"]


@pytest.mark.parametrize("notebook", NOTEBOOK_FILES, ids=lambda p: p.stem)
def test_committed_without_outputs_and_with_literal_parameters(notebook):
    cells = json.loads(notebook.read_text())["cells"]
    assert cells[0]["cell_type"] == "markdown" and "".join(cells[0]["source"]).startswith("# ")
    for cell in cells:
        if cell["cell_type"] == "code":
            assert not cell["outputs"] and cell["execution_count"] is None, "strip the outputs"
    tagged = [c for c in cells if "parameters" in c["metadata"].get("tags", [])]
    assert len(tagged) == 1, "exactly one cell tagged 'parameters'"
    values = {}
    for node in ast.parse("".join(tagged[0]["source"])).body:
        assert isinstance(node, ast.Assign), "the parameters cell holds assignments only"
        value = ast.literal_eval(node.value)  # literals only: papermill replaces them
        values.update({target.id: value for target in node.targets})
    assert REQUIRED_PARAMETERS <= set(values)
    # Explore freely, publish deliberately: a run by hand writes under build/, never figures/.
    assert values["out_dir"] == f"build/explore/{notebook.stem}"
    assert all(not str(v).startswith("figures") for k, v in values.items() if k.endswith("_dir"))


def ensure_models(directory, study_file, scratch):
    """Chapters 05 and 06 run into ``directory`` unless their data and models are there (in
    `make report`, and in this module's order, they ran before the chapters that need them)."""
    for prefix, ready in (("05", directory / "data_dir" / "id_test.npz"),
                          ("06", directory / "models_dir" / "id")):
        if not ready.exists():
            (nb,) = [n for n in NOTEBOOK_FILES if n.name.startswith(prefix)]
            run_chapter(nb, scratch / nb.name, {
                "smoke": True, "study_file": study_file, "out_dir": str(scratch / prefix),
                **{k: str(directory / k) for k in ("data_dir", "models_dir", "sweeps_dir")
                   if k in papermill.inspect_notebook(str(nb))}})


@pytest.fixture(scope="module")
def shared(tmp_path_factory):
    """Data and model directories shared by the chapters of one test run, as in `make report`:
    chapter 06 trains on chapter 05's data, chapter 07 tests chapter 06's models."""
    return tmp_path_factory.mktemp("shared")


#: Tests that share the data and models of a chain of chapters (05 → 06 → 07 → 08) run in one
#: pytest-xdist worker (`make test` runs two, `--dist loadgroup`); the module's fixtures are
#: per worker.
CHAIN = pytest.mark.xdist_group("study-chain")


def _chained(notebook):
    uses_data = {"data_dir", "models_dir", "study_files"} & set(papermill.inspect_notebook(str(notebook)))
    return pytest.param(notebook, marks=[CHAIN] if uses_data else [], id=notebook.stem)


@pytest.mark.notebook
@pytest.mark.parametrize("notebook", [_chained(nb) for nb in NOTEBOOK_FILES])
def test_runs_in_smoke_mode_and_writes_its_figures(notebook, tmp_path, shared):
    out = tmp_path / "out"
    executed = tmp_path / notebook.name
    parameters = {"smoke": True, "out_dir": str(out)}
    declared = papermill.inspect_notebook(str(notebook))
    for name in ("recordings_dir", "data_dir", "models_dir", "sweeps_dir"):   # nothing written into the checkout
        if name in declared:
            parameters[name] = str(shared / name)
    if "study_files" in declared:       # the comparison, here of one arm (both: test below)
        study = "params/studies/intelbot5.yaml"
        parameters.update(study_files=[study], data_dirs=[str(shared / "data_dir")],
                          models_dirs=[str(shared / "models_dir")])
        ensure_models(shared, study, tmp_path)
    elif notebook.name.startswith("07"):
        ensure_models(shared, "params/studies/intelbot5.yaml", tmp_path)
    run_chapter(notebook, executed, parameters)
    assert str(ROOT) not in executed.read_text(), "no absolute path of the checkout"
    check_page(notebook, executed, tmp_path)
    outputs = [o for c in json.loads(executed.read_text())["cells"] for o in c.get("outputs", [])]
    # No value or print shows a path of the machine that ran it (prose names its directories
    # deliberately, relative to the checkout when they lie in it).
    shown = json.dumps([o for o in outputs if o["output_type"] in ("execute_result", "stream")])
    assert str(tmp_path) not in shown and str(shared) not in shown, "an output shows a path of this machine"
    assert any("image/png" in o.get("data", {}) for o in outputs), "figures show in the chapter"
    prefix = notebook.name[:2]
    figures = sorted(out.glob("*.png"))
    tables = sorted((out / "tables").glob("*.csv"))
    assert figures and tables
    # What a chapter saves, its page shows, numbered (the long tables of every row are for machines: their
    # reading copies are shown)
    shown = {name for _, name in numbered_outputs(executed)}
    unshown = {p.stem for p in figures + tables} - shown - LONG_TABLES
    assert not unshown, f"saved but not shown on the page: {sorted(unshown)}"
    for path in figures + tables:
        assert path.name.startswith(f"{prefix}_") and path.stat().st_size > 0
    for table in tables:
        assert table.with_suffix(".md").exists()


ROBOT_CHAPTERS = [nb for nb in NOTEBOOK_FILES
                  if "robot_file" in papermill.inspect_notebook(str(nb))]


#: Every robot chapter for the SO-101 (read from its URDF); for the 6-joint Puma 560, the ones
#: whose code depends on the joint count beyond what the unit tests check (the IK chapter's
#: solvers are tested on the Puma in test_ik, and its smoke run is the suite's slowest).
OTHER_ROBOT_RUNS = [(nb, "so101") for nb in ROBOT_CHAPTERS] + \
    [(nb, "puma560") for nb in ROBOT_CHAPTERS if not nb.name.startswith("02")]


@pytest.mark.notebook
@pytest.mark.parametrize("notebook, robot", OTHER_ROBOT_RUNS,
                         ids=[f"{nb.stem}-{robot}" for nb, robot in OTHER_ROBOT_RUNS])
def test_runs_for_another_shipped_robot_without_touching_figures(notebook, robot, tmp_path):
    """A chapter takes any shipped robot (the 6-joint Puma 560, the SO-101 read from its
    URDF), and a run by hand never writes into figures/."""
    before = {p: p.stat().st_mtime_ns for p in FIGURES.rglob("*")}
    parameters = {"smoke": True, "out_dir": str(tmp_path / "out"),
                  "robot_file": f"params/robots/{robot}.yaml"}
    for name in ("recordings_dir", "data_dir", "models_dir", "sweeps_dir"):
        if name in papermill.inspect_notebook(str(notebook)):
            parameters[name] = str(tmp_path / name)
    run_chapter(notebook, tmp_path / notebook.name, parameters)
    assert robot in (tmp_path / notebook.name).read_text()
    check_page(notebook, tmp_path / notebook.name, tmp_path)
    assert {p: p.stat().st_mtime_ns for p in FIGURES.rglob("*")} == before


STUDY_CHAPTERS = [nb for nb in NOTEBOOK_FILES
                  if "study_file" in papermill.inspect_notebook(str(nb))]


@pytest.fixture(scope="module")
def so101_shared(tmp_path_factory):
    return tmp_path_factory.mktemp("so101")


@CHAIN
@pytest.mark.notebook
@pytest.mark.parametrize("notebook", STUDY_CHAPTERS, ids=lambda p: p.stem)
def test_the_study_chapters_run_for_the_so101(notebook, so101_shared):
    """Chapters 05–07 in order on the SO-101's study: its data, its models, their tests."""
    parameters = {"smoke": True, "out_dir": str(so101_shared / f"out_{notebook.stem}"),
                  "study_file": "params/studies/so101.yaml"}
    for name in ("recordings_dir", "data_dir", "models_dir", "sweeps_dir"):
        if name in papermill.inspect_notebook(str(notebook)):
            parameters[name] = str(so101_shared / name)
    if notebook.name.startswith("07"):
        ensure_models(so101_shared, "params/studies/so101.yaml", so101_shared)
    run_chapter(notebook, so101_shared / notebook.name, parameters)
    assert "so101" in (so101_shared / notebook.name).read_text()
    check_page(notebook, so101_shared / notebook.name, so101_shared)
    assert sorted((so101_shared / f"out_{notebook.stem}").glob("*.png"))


@CHAIN
@pytest.mark.notebook
def test_the_comparison_of_the_two_arms_runs(shared, so101_shared, tmp_path):
    """Chapter 08 on both studies' smoke data and models (made by the tests above)."""
    studies = {"params/studies/intelbot5.yaml": shared, "params/studies/so101.yaml": so101_shared}
    for study, directory in studies.items():
        ensure_models(directory, study, tmp_path)
    (compare,) = [nb for nb in NOTEBOOK_FILES if "study_files" in papermill.inspect_notebook(str(nb))]
    run_chapter(compare, tmp_path / compare.name, {
        "smoke": True, "out_dir": str(tmp_path / "out"), "study_files": list(studies),
        "data_dirs": [str(d / "data_dir") for d in studies.values()],
        "models_dirs": [str(d / "models_dir") for d in studies.values()]})
    check_page(compare, tmp_path / compare.name, tmp_path)
    table = (tmp_path / "out" / "tables" / f"{compare.name[:2]}_arms.csv").read_text()
    assert table.splitlines()[0] == "quantity,intelbot5,so101"
    assert "learned IK, worst joint RMSE [deg]" in table
    # One source (issue 43): every result chapter 8 and the verdicts state is chapter 7's summary's, in the smoke run too
    from test_one_source import results_disagreeing
    results = {arm: d / "models_dir" / "results" / "tables" for arm, d in zip(("intelbot5", "so101"), studies.values())}
    differing = results_disagreeing({arm: r / "07_summary.csv" for arm, r in results.items()},
                                    tmp_path / "out" / "tables" / f"{compare.name[:2]}_learned.csv",
                                    {arm: r / "07_verdict.csv" for arm, r in results.items()})
    assert not differing, f"a result stated twice, differently: {differing}"


@pytest.mark.notebook
@CHAIN
def test_chapter_06_leaves_the_built_arm_beside_the_measured_arms_models(shared, tmp_path):
    """The built arm the measured-arm models were trained on is a robot file beside them, which
    loads into the same dynamics as the study's built arm (an independent engine can take it)."""
    import numpy as np
    from nfarm.model.dynamics import rnea
    from nfarm.model.robot import load_robot
    from nfarm.study import datasets, study_files

    ensure_models(shared, "params/studies/intelbot5.yaml", tmp_path)
    built = load_robot(shared / "models_dir" / "id_measured" / "built_arm.yaml")
    study = study_files.smoke_study(study_files.load_study("params/studies/intelbot5.yaml"))
    expected, _ = datasets.built_arm(study)
    q, qd, qdd = np.random.default_rng(0).normal(size=(3, 20, expected.n))
    for drive in (False, True):                      # its links, and its drives' armature and friction
        np.testing.assert_array_equal(rnea(built, q, qd, qdd, drive=drive), rnea(expected, q, qd, qdd, drive=drive))
    assert not np.array_equal(built.mass, study.robot.mass), "the built arm, not the model"
    import yaml
    offsets = yaml.safe_load((shared / "models_dir" / "id_measured" / "built_arm_offsets.yaml").read_text())
    assert offsets["zero_offset_nm"] == datasets.built_arm(study)[1].tolist()
    assert (shared / "models_dir" / "id_measured" / "structure_informed" / "anfis").is_dir()


def test_chapter_06_never_reads_a_test_split():
    """Chapter 06 chooses every model on validation data: no cell of the chapter (the course's
    exercise cells aside, which the report removes) names a test split — a data set file
    ``*_test``, a ``"test"`` split or a sweep cell of ``split="test"``."""
    nb = json.loads((NOTEBOOKS / "06_anfis_training.ipynb").read_text(encoding="utf-8"))
    named = []
    for k, cell in enumerate(nb["cells"]):
        if cell["cell_type"] != "code" or set(cell["metadata"].get("tags", [])) & set(COURSE_TAGS):
            continue
        for node in ast.walk(ast.parse("".join(cell["source"]))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and \
                    (node.value == "test" or node.value.endswith("_test") or "_test." in node.value):
                named.append((k, node.value))
            if isinstance(node, ast.Name) and node.id.endswith("_test"):
                named.append((k, node.id))
    assert not named, named


@pytest.mark.parametrize("notebook", NOTEBOOK_FILES, ids=lambda p: p.stem)
def test_visible_code_uses_no_name_defined_only_in_hidden_cells(notebook):
    """A reader of a page sees the code of every cell but the prose cells (``remove-input``):
    a visible cell must not use a name that only a hidden cell defines."""
    hidden, visible, problems = set(), set(), []
    for k, cell in enumerate(json.loads(notebook.read_text(encoding="utf-8"))["cells"]):
        tags = set(cell["metadata"].get("tags", []))
        if cell["cell_type"] != "code" or tags & set(COURSE_TAGS):
            continue
        defined, used = set(), set()
        for node in ast.walk(ast.parse("".join(cell["source"]))):
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                defined.add(node.name)
            elif isinstance(node, ast.arg):
                defined.add(node.arg)
            elif isinstance(node, ast.Name):
                (defined if isinstance(node.ctx, ast.Store) else used).add(node.id)
        if tags & {"remove-input", "remove-cell"}:
            hidden |= defined - visible
        else:
            problems += [(k, name) for name in sorted((used - defined) & (hidden - visible))]
            visible |= defined
    assert not problems, f"visible cells use names defined in hidden ones: {problems}"


#: Two arms the project writes as URDFs, each through `add-arm` and a smoke edition of its chapters
#: (issue 44): one in the closed form's class (a CAD export's rounded π between its elbow and wrist
#: pitch axes, converted with the tilt in a fixed transform: the closed form's branches polished by
#: LM), one outside it (the wrist turning across the pitch axes: LM alone).
ADDED_ARMS = {"rounded": "0 1 7.346410206832132e-06", "skew": "1 0 0"}
#: The chapters an added arm's edition runs here: every robot and study chapter but the IK
#: solvers' comparison (04, run on three shipped arms above), and the comparison of the arms (08)
#: on the added arm alone (`make report ARM=N` runs it over the arms present).
ADDED_CHAPTERS = ("01", "02", "03", "05", "06", "07", "08")


@pytest.fixture(scope="module")
def added_arms(tmp_path_factory):
    """Each of :data:`ADDED_ARMS` added by `add-arm` into parameter directories of its own (made
    once per worker, on first use); its chapters' data and models shared as in `make report`."""
    from test_add_arm import write_arm

    from nfarm.study.add_arm import add_arm

    made = {}

    def arm(name):
        if name not in made:
            root = tmp_path_factory.mktemp(f"added_{name}")
            urdf = write_arm(root / f"{name}.urdf", wrist_axis=ADDED_ARMS[name], dynamics=True)
            add_arm(urdf, tip="tool_link", params=root / "params", targets=300, say=lambda line: None)
            made[name] = root
        return made[name]
    return arm


@pytest.mark.notebook
@pytest.mark.parametrize("arm, notebook", [
    pytest.param(arm, nb, marks=pytest.mark.xdist_group(f"added-{arm}"), id=f"{nb.stem}-{arm}")
    for arm in ADDED_ARMS for nb in NOTEBOOK_FILES if nb.name[:2] in ADDED_CHAPTERS])
def test_an_added_arms_edition_runs_in_smoke_mode(arm, notebook, added_arms):
    """A new arm, from its URDF through `add-arm`, gets a whole edition: the robot chapters on its
    robot file, the study chapters in order on its study file (05's data, 06's models, 07's
    tests, 08's comparison), each page checked as the shipped editions' are and naming the arm."""
    root = added_arms(arm)
    declared = papermill.inspect_notebook(str(notebook))
    out = root / f"out_{notebook.stem}"
    parameters = {"smoke": True, "out_dir": str(out)}
    study = str(root / "params" / "studies" / f"{arm}.yaml")
    if "study_file" in declared:
        parameters["study_file"] = study
    elif "study_files" in declared:                # chapter 08: the arms present, here the added one
        parameters |= {"study_files": [study], **{f"{name}s": [str(root / name)] for name in ("data_dir", "models_dir")}}
    else:
        parameters["robot_file"] = str(root / "params" / "robots" / f"{arm}.yaml")
    for name in ("recordings_dir", "data_dir", "models_dir", "sweeps_dir"):
        if name in declared:
            parameters[name] = str(root / name)
    if notebook.name[:2] in ("07", "08"):
        ensure_models(root, study, root)
    if notebook.name.startswith("08") and not (root / "models_dir" / "results" / "tables" / "07_summary.csv").exists():
        (chapter_07,) = [n for n in NOTEBOOK_FILES if n.name.startswith("07")]
        run_chapter(chapter_07, root / "scratch_07.ipynb", {      # chapter 08 reads chapter 07's verdict and summary
            "smoke": True, "study_file": study, "out_dir": str(root / "scratch_07"),
            **{n: str(root / n) for n in ("data_dir", "models_dir", "sweeps_dir", "recordings_dir")}})
    executed = root / notebook.name
    run_chapter(notebook, executed, parameters)
    assert arm in executed.read_text()
    check_page(notebook, executed, root)
    assert sorted(out.glob("*.png")) and sorted((out / "tables").glob("*.csv"))
    if arm == "skew" and notebook.name[:2] in ("05", "06", "07"):
        # The exercises work for an arm outside the class (chapter 5's region, chapter 7's model on the seven inputs), or
        # say in a sentence why not (chapter 6's two exercises in the arm's plane): every worked solution passes its check
        import nbformat

        from nfarm.publishing.course import check_results, exercise_notebook
        source, ran = root / f"exercises_{notebook.name}", root / f"exercises_run_{notebook.name}"
        nbformat.write(exercise_notebook(notebook), source)
        run_notebook(source, ran, {**parameters, "out_dir": str(root / f"exercises_{notebook.stem}")})
        results = check_results(ran)
        assert results and all(r["passed"] for r in results), [r for r in results if not r["passed"]]
        if notebook.name.startswith("06"):
            assert "exercise 6.1 does not apply to skew" in ran.read_text()
    if notebook.name.startswith("07"):
        # The contest's rivals are chapter 7's baselines: on an arm the arm's plane cannot describe (skew)
        # they take the dissertation's seven inputs, as its ANFIS does
        from conftest import load_quietly
        from nfarm.study.contest import saved_rivals

        rivals = saved_rivals(load_quietly(root / "params" / "robots" / f"{arm}.yaml"), root / "models_dir")
        assert rivals and {r.encoding for r in rivals.values()} == {"quat_xyz" if arm == "skew" else "arm_plane"}
