"""Model first (issue 29, item 1): a model file is taken by its content wherever a file is taken,
and every message on a model's path speaks of the model.

``certify FILE``, ``simulate FILE``, ``report FILE`` and the API's ``certify("FILE")`` take a model
file without ``--model`` (recognised by its ``[model]`` or ``[dynamics]`` table); a paper gain file
still goes the paper's way. ``--set mu 1`` says ``use --set mu=1``; a paper flag with a model file
names itself as the paper's; ``--help`` presents a tool for any closed loop.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.language.modelfile import is_model_file
from tests.conftest import PAPER_TOML, ROOT

app._register_commands()
RUNNER = CliRunner()
MODEL = ROOT / "examples" / "models" / "fossil-poly2.toml"


def invoke(*args: str) -> tuple[int, str]:
    done = RUNNER.invoke(app.cli, list(args), env={"COLUMNS": "200"})
    return done.exit_code, done.output


def test_a_model_file_is_recognised_by_its_content(tmp_path: Path) -> None:
    assert is_model_file(MODEL)
    assert not is_model_file(PAPER_TOML)
    assert not is_model_file(ROOT / "examples" / "models" / "sweeps" / "boxes-oscillator.toml")  # a spec naming one
    only_dynamics = tmp_path / "bare.toml"
    only_dynamics.write_text('[dynamics]\nx = "-x"\n')
    assert is_model_file(only_dynamics)
    for text in ("not toml [", "", "[gains]\nalpha_d = 1\n"):
        other = tmp_path / "other.toml"
        other.write_text(text)
        assert not is_model_file(other)
    assert not is_model_file(tmp_path / "missing.toml") and not is_model_file(tmp_path) and not is_model_file(3)


def test_certify_takes_a_model_file_without_model_flag(tmp_path: Path) -> None:
    out = tmp_path / "c.json"
    code, text = invoke("certify", str(MODEL), "--out", str(out))
    assert code == 0, text
    doc = json.loads(out.read_text())
    assert doc["kind"] == "lyapcheck-model-certificate" and doc["verdict"] == "certified"
    code_flag, _ = invoke("certify", "--model", str(MODEL), "--classes", "linearization")
    assert code_flag == 0  # --model keeps working
    code_paper, text_paper = invoke("certify", str(PAPER_TOML), "--classes", "quick")
    assert code_paper in (0, 1) and "prop41" in text_paper  # a paper gain file still goes the paper's way


def test_the_api_takes_a_model_file_by_path() -> None:
    from lyapcheck import certify

    result = certify(str(MODEL), classes="linearization,quadratic")
    assert result.dynamics == "model" and result.verdict == "certified"
    assert set(result.conditions) == {"linearization", "quadratic"}


def test_simulate_and_report_take_a_model_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    code, text = invoke("simulate", str(MODEL), "--x0", "x=1 y=0", "--json")
    assert code == 0, text
    assert json.loads(text)["starts"] == [{"x": 1.0, "y": 0.0}]  # "x=1 y=0": split before each NAME=
    monkeypatch.chdir(tmp_path)
    code, text = invoke("report", str(MODEL))
    assert code == 0, text
    assert (tmp_path / "fossil-poly2.html").is_file()


def test_a_sweep_of_a_model_file_says_what_a_spec_is(tmp_path: Path) -> None:
    code, text = invoke("sweep", str(MODEL), "--out", str(tmp_path / "s.zarr"))
    assert code == 2 and "is a model file" in text and "[sweep] model" in text and "docs/model-sweeps.md" in text
    assert not (tmp_path / "s.zarr").exists()


@pytest.mark.parametrize("args, says", [
    (("certify", "MODEL", "--set", "mu", "1"), "use --set mu=1"),
    (("certify", "--model", "MODEL", "--set", "mu", "1"), "use --set mu=1"),
    (("simulate", "MODEL", "--set", "mu", "2"), "use --set mu=2"),
    (("simulate", "MODEL", "--x0", "x=1", "y=0"), 'use --x0 "x=1 y=0"'),
    (("certify", "MODEL", "--worst-case"), "--worst-case: is a flag of the paper's loop"),
    (("certify", "MODEL", "--alpha-d", "3"), "use --set NAME=VALUE"),
    (("certify", "MODEL", "--dynamics", "printed"), "--dynamics: is a flag of the paper's loop"),
    (("certify", "MODEL", "--classes", "quick"), "'quick' is the paper's selection"),
    (("simulate", "MODEL", "--preset", "paper-ilos"), "--preset: is a flag of the paper's loop"),
    (("certify", "MODEL", "--model", "MODEL"), "FILE or --model FILE, not both"),
    (("certify", "MODEL", "PAPER"), "is the only input file"),
])
def test_messages_on_a_models_path_speak_of_the_model(args: tuple[str, ...], says: str) -> None:
    words = [str(MODEL) if a == "MODEL" else str(PAPER_TOML) if a == "PAPER" else a for a in args]
    code, text = invoke(*words)
    assert code == 2, text
    lines = text.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in text
    assert says in lines[0], lines[0]


def test_the_help_presents_a_general_tool() -> None:
    code, text = invoke("--help")
    assert code == 0
    first = text.split("\n\n")[1].strip()
    assert first.startswith("Machine-checked stability answers for any polynomial or rational closed")
    assert "model file" in first and "docs/model-files.md" in first
    code, text = invoke("certify", "--help")
    options = text[text.index("Options:"):]
    assert options.index("--model") < options.index("--alpha-d") < options.index("--worst-case")
    assert "../shared" not in text and "DESIGN.md" not in text
