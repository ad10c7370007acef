"""The course edition (nfarm.publishing.course): exercises with worked solutions and checks, the student
build without solutions or outputs, the teacher build with every check passing, and every check
failing with its message on a deliberately wrong answer."""

from __future__ import annotations

import json

import nbformat
import numpy as np
import papermill
import pytest

from nfarm.publishing.course import (CHECK_MIME, TAGS, build_course, check, check_function, check_results,
                                     check_that, exercise_notebook)
from nfarm.infra.paths import NOTEBOOKS
from nfarm.infra.notebook_runs import chapters, run_notebook

WITH_EXERCISES = [nb for nb in chapters(NOTEBOOKS)
                  if any("exercise" in c.get("metadata", {}).get("tags", [])
                         for c in json.loads(nb.read_text())["cells"])]


def tags(cell) -> set[str]:
    return set(cell.get("metadata", {}).get("tags", []))


def test_every_chapter_has_three_to_five_exercises():
    assert [nb.name for nb in WITH_EXERCISES] == [nb.name for nb in chapters(NOTEBOOKS)]
    for nb in WITH_EXERCISES:
        cells = json.loads(nb.read_text())["cells"]
        solutions = [c for c in cells if "solution" in tags(c)]
        checks = [c for c in cells if "check" in tags(c)]
        assert 3 <= len(solutions) <= 5 and len(checks) == len(solutions), nb.name
        assert all(c.get("metadata", {}).get("nfarm", {}).get("wrong") for c in solutions), nb.name
        facts = json.loads(nb.read_text())["metadata"]["nfarm"]["course"]
        assert facts["goals"] and isinstance(facts["prerequisites"], list) and facts["minutes"] > 0
        # The exercises come last: the chapter's own cells run the same with or without them.
        first = next(k for k, c in enumerate(cells) if tags(c) & set(TAGS))
        assert all(tags(c) & set(TAGS) for c in cells[first:]), nb.name


STAGE = "nfarm_test_stage"


def _answered_three_ways(notebook):
    """The chapter's exercise notebook with each check run three times: before its exercise is
    answered (a student who runs the notebook sees "not answered yet", not a traceback), after
    the deliberately wrong answer, and after the worked solution. One run of the set-up serves
    the three; each check cell is marked with its stage."""
    nb = exercise_notebook(notebook)
    cells = []
    for k, cell in enumerate(nb.cells):
        if "solution" in tags(cell):
            following = next(c for c in nb.cells[k + 1:] if "check" in tags(c))
            staged = lambda stage: nbformat.v4.new_code_cell(   # noqa: E731
                following.source, metadata={"tags": ["check"], STAGE: stage})
            wrong = nbformat.v4.new_code_cell(cell.metadata["nfarm"]["wrong"], metadata={"tags": ["solution"]})
            cells += [staged("unanswered"), wrong, staged("wrong")]
        elif "check" in tags(cell):
            cell.metadata[STAGE] = "worked"
        cells.append(cell)
    nb.cells = cells
    return nb


def _verdicts_by_stage(executed) -> dict[str, list[dict]]:
    found: dict[str, list[dict]] = {"unanswered": [], "wrong": [], "worked": []}
    for cell in json.loads(executed.read_text(encoding="utf-8"))["cells"]:
        stage = cell.get("metadata", {}).get(STAGE)
        for output in cell.get("outputs", []):
            verdict = output.get("data", {}).get(CHECK_MIME)
            if verdict and stage:
                found[stage].append(verdict)
    return found


@pytest.mark.notebook
@pytest.mark.parametrize("notebook", WITH_EXERCISES, ids=lambda p: p.stem)
def test_every_check_passes_on_its_solution_and_fails_on_a_wrong_answer(notebook, tmp_path):
    source = tmp_path / notebook.name
    nbformat.write(_answered_three_ways(notebook), source)
    executed = tmp_path / "executed.ipynb"
    parameters = {"smoke": True, "out_dir": str(tmp_path / "out")}
    declared = papermill.inspect_notebook(str(notebook))
    parameters.update({k: str(tmp_path / k) for k in ("data_dir", "models_dir", "recordings_dir", "sweeps_dir")
                       if k in declared})       # nothing written into the checkout
    run_notebook(source, executed, parameters)
    staged = _verdicts_by_stage(executed)
    assert sum(len(v) for v in staged.values()) == len(check_results(executed)), "every check is staged"
    solutions = sum("solution" in tags(c) for c in json.loads(notebook.read_text())["cells"])
    exercises = {v["exercise"].split()[0] for v in staged["worked"]}
    assert len(exercises) == solutions
    assert all(v["passed"] for v in staged["worked"]), [v for v in staged["worked"] if not v["passed"]]
    unanswered = [v for v in staged["unanswered"] if v["message"].startswith("not answered yet")]
    assert {v["exercise"].split()[0] for v in unanswered} == exercises
    assert not any(v["passed"] for v in staged["unanswered"])
    # Every exercise fails at least one of its checks on the wrong answer, with a message saying what is wrong.
    failed = [v for v in staged["wrong"] if v["message"].startswith("not yet: ")]
    assert {v["exercise"].split()[0] for v in failed} == exercises


def test_the_student_build_has_no_solutions_and_no_outputs(tmp_path):
    out = build_course(tmp_path, teacher=False)
    students = sorted((out / "student").glob("*.ipynb"))
    assert [p.name for p in students] == [nb.name for nb in WITH_EXERCISES]
    for path in students:
        nb = nbformat.read(path, 4)
        assert not [c for c in nb.cells if "solution" in tags(c)]
        assert [c for c in nb.cells if "check" in tags(c)]
        assert all(not c.get("outputs") and c.get("execution_count") is None
                   for c in nb.cells if c.cell_type == "code")
    index = (out / "index.html").read_text()
    assert all(f"student/{p.name}" in index for p in students) and "minutes" in index


@pytest.mark.notebook
def test_the_teacher_build_runs_with_every_check_passing(tmp_path):
    out = build_course(tmp_path, smoke=True, only=["04"])
    executed = out / "teacher" / "04_anfis_method.ipynb"
    verdicts = check_results(executed)
    assert verdicts and all(v["passed"] for v in verdicts)
    assert (out / "teacher" / "04_anfis_method.html").stat().st_size > 0
    assert "with solutions" in (out / "index.html").read_text()


def test_the_command_line_refuses_an_unknown_chapter(tmp_path, capsys):
    from nfarm.__main__ import main

    assert main(["course", "--out", str(tmp_path), "--only", "99", "--no-teacher"]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("course: no chapter 99 (chapters: 01, ") and "\n" not in err
    assert not (tmp_path / "index.html").exists()
    assert main(["course", "--out", str(tmp_path), "--only", "01", "--no-teacher"]) == 0
    assert [p.name for p in (tmp_path / "student").iterdir()] == ["01_dh_model.ipynb"]


def test_the_report_leaves_the_exercises_out(tmp_path):
    (notebook,) = [nb for nb in WITH_EXERCISES if nb.name.startswith("04")]
    source = tmp_path / notebook.name
    nbformat.write(exercise_notebook(notebook), source)
    run_notebook(source, tmp_path / "out.ipynb", {"smoke": True}, remove_tags=TAGS)
    cells = nbformat.read(tmp_path / "out.ipynb", 4).cells
    assert cells and not [c for c in cells if tags(c) & set(TAGS)]
    assert not check_results(tmp_path / "out.ipynb")


# --------------------------------------------------------------------------------------------
# The checks themselves (outside a kernel: IPython's display prints)


@pytest.mark.parametrize("answer, expected, message", [
    (None, 1.0, "not answered yet"),
    (1.1, 1.0, "not yet: 1.1 m is off by 0.1 m"),
    ([1, 2], [1, 2, 3], "not yet: expected shape (3,), got (2,)"),
    ("text", 1.0, "not yet: expected a number, got str"),
    (float("nan"), 1.0, "not yet: the answer holds NaN or infinity"),
    (1.0, "gauss", "not yet: expected a text, got float"),
    ("Gbell", "gauss", "not yet: 'Gbell' is not the answer"),
])
def test_a_wrong_answer_gets_a_message_not_a_traceback(answer, expected, message, capsys):
    assert check("9.9", answer, expected, unit="m") is False
    assert message in capsys.readouterr().out


def test_a_right_answer_passes(capsys):
    assert check("9.9", np.array([1.0, 2.0 + 1e-9]), [1.0, 2.0])
    assert check("9.9", " GAUSS ", "gauss")
    assert "✅ Exercise 9.9: correct" in capsys.readouterr().out


def test_a_students_function_that_raises_is_reported(capsys):
    def broken(x):
        raise ZeroDivisionError("division by zero")

    assert check_function("9.9", broken, lambda x: x, [(1.0,)]) is False
    assert "on case 1 your function raised ZeroDivisionError: division by zero" in capsys.readouterr().out
    assert check_function("9.9", lambda x: 2 * x, lambda x: 2.0 * x, [(1.0,), (np.arange(3),)])
    assert check_function("9.9", lambda x: None, lambda x: x, [(1.0,)]) is False
    assert "not answered yet: your function returns None" in capsys.readouterr().out
    assert check_that("9.9", None, fail="x") is False
    assert check_that("9.9", False, fail="the step is not along Jᵀe") is False
    assert "not yet: the step is not along Jᵀe" in capsys.readouterr().out


def test_the_teachers_guide_has_every_chapters_goals_and_exercises():
    guide = (NOTEBOOKS.parent / "docs" / "teaching.md").read_text()
    for nb in WITH_EXERCISES:
        data = json.loads(nb.read_text())
        for goal in data["metadata"]["nfarm"]["course"]["goals"]:
            assert f"- {goal}\n" in guide, (nb.name, goal)
        numbers = {line.split()[2] for c in data["cells"] if c["cell_type"] == "markdown"
                   for line in "".join(c["source"]).splitlines() if line.startswith("### Exercise ")}
        for number in numbers:
            assert f"**{number}**" in guide, (nb.name, number)
