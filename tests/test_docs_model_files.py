"""docs/model-files.md, the model-file reference, as a user runs it.

Every fenced ```toml block of the page is a whole model file (its first line names it, ``#
NAME.toml``) and must parse; every line of a fenced ```bash block is a ``lyapcheck`` command that
states its exit code (``# exit N``), and the cheap ones are run here through the command line
(click's CliRunner), in a scratch directory holding the page's TOML files, with the exit code the
page states; where the page names the verdict (``# exit 0: certified_nominal``) it is checked too.
The limits the page quotes are the code's.
"""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.surfaces.certify import VERDICTS
from lyapcheck.models.language.modelfile import parse_model
from tests.conftest import ROOT

app._register_commands()
RUNNER = CliRunner()
DOC = ROOT / "docs" / "model-files.md"
TEXT = DOC.read_text()

#: the page's commands run here, in this order (a later one may read what an earlier one wrote),
#: each exactly as on the page (without its comment). The others (a region of attraction, a box of
#: the Van der Pol oscillator, the worst-case search, a report, a sweep) take seconds to minutes;
#: the tests of their own modules run them
CHEAP = (
    "lyapcheck certify examples/models/fossil-poly2.toml",
    "lyapcheck certify examples/models/unstable-van-der-pol.toml",
    "lyapcheck certify multiplicative.toml",
    "lyapcheck certify multiplicative.toml --set d=0.5",
    "lyapcheck certify examples/models/linear-scalar-disturbed.toml",
    "lyapcheck certify examples/models/pendulum-digital-pd.toml",
    "lyapcheck certify examples/models/pendulum-digital-pd-slow.toml",
    "lyapcheck certify examples/models/pendulum-digital-tanh-policy.toml",
    'lyapcheck certify examples/models/damped-oscillator.toml --box "k=0.8..1.2" --classes quadratic',
    'lyapcheck certify examples/models/drake-cubic-polynomial.toml --candidate "x**2" --out cubic.json',
    "lyapcheck verify cubic.json",
    "lyapcheck certify examples/models/sosdemo2-rational.toml --classes linearization,sos_gas --json",
    'lyapcheck certify examples/models/fossil-poly2.toml --candidate "x**2 + y**2"',
    "lyapcheck certify examples/models/unstable-van-der-pol.toml --classes linearization",
    "lyapcheck certify examples/models/damped-oscillator.toml --classes linearization --minimize c=-1..1",
    "lyapcheck tune examples/models/linear-scalar-disturbed.toml --box a=1..4 --objective bound:y --grid 2",
    "lyapcheck tune examples/models/linear-scalar-disturbed.toml --box a=1..4 --objective bound:y --grid 2 --out tuned.json",
    "lyapcheck report tuned.json --html tuned.html --pdf tuned.pdf",
    "lyapcheck certify examples/models/damped-oscillator.toml --classes linearization --minimize c=-1..1 --out smallest-c.json",
    "lyapcheck report smallest-c.json --html smallest-c.html",
    "lyapcheck tune examples/models/damped-oscillator.toml --box k=1..2 --objective bound:x1",
    "lyapcheck tune examples/models/pid-hardening-spring.toml --box kp=0.5..4 --box ki=0.25..2 --objective local_decay_rate",
    'lyapcheck certify examples/models/pid-hardening-spring.toml --box "kp=1.5..2.5" --box "ki=0.5..1.5" --classes linearization',
    'lyapcheck certify examples/models/pid-hardening-spring.toml --box "kp=1..2" --box "ki=1..2" --classes linearization',
    "lyapcheck certify examples/models/van-der-pol-reversed.toml --set nu=2",
    'lyapcheck certify examples/models/van-der-pol-reversed.toml --candidate "x1**2 + x2**2 + 1"',
    'lyapcheck simulate examples/models/van-der-pol-reversed.toml --x0 "x1=0.5,x2=0"',
    'lyapcheck simulate examples/models/van-der-pol-reversed.toml --x0 "x1=2.5,x2=0"',
    "lyapcheck simulate examples/models/damped-oscillator.toml --grid 3",
    "lyapcheck certify examples/models/discrete-stable-map.toml",
    "lyapcheck certify examples/models/discrete-local-map.toml --classes roa",
    "lyapcheck certify examples/models/fossil-dt-two-room-temp.toml",
    "lyapcheck certify examples/models/fossil-dt-ahmadi.toml",
    "lyapcheck certify examples/models/discrete-unstable-map.toml",
    "lyapcheck certify examples/models/discrete-safety-map.toml --classes barrier",
    "lyapcheck certify examples/models/discrete-unsafe-map.toml --classes barrier",
)


def fenced(language: str) -> list[str]:
    """The bodies of the page's fenced blocks in ``language``."""
    return [m.group(2) for m in re.finditer(r"^```(\w*)\n(.*?)^```", TEXT, re.S | re.M) if m.group(1) == language]


def toml_files() -> dict[str, str]:
    """The page's TOML blocks by the file name on their first line."""
    out = {}
    for body in fenced("toml"):
        if re.search(r"^# refused: ", body, flags=re.M):
            continue  # a file the page shows refused (tests/test_model_units.py checks each refusal)
        first = body.splitlines()[0]
        match = re.match(r"#\s*([\w.-]+\.toml)\b", first)
        assert match, f"a TOML block must name its file on its first line ('# NAME.toml'): {first!r}"
        out[match.group(1)] = body
    return out


def command_lines() -> list[str]:
    return [line.strip() for body in fenced("bash") for line in body.splitlines() if line.strip()]


def command(line: str) -> str:
    """A command line without its comment."""
    return line.split("#", 1)[0].strip()


def stated(line: str) -> tuple[list[str], int, str]:
    """A command line's arguments (after ``lyapcheck``), its stated exit code and what follows it."""
    words = shlex.split(line, comments=True)
    match = re.search(r"#\s*exit (\d+)(.*)$", line)
    assert words[0] == "lyapcheck" and match, f"not a command with its exit code: {line!r}"
    return words[1:], int(match.group(1)), match.group(2).lstrip(":, ").strip()


def test_every_toml_block_is_a_model_file_that_parses() -> None:
    files = toml_files()
    refused = [body for body in fenced("toml") if re.search(r"^# refused: ", body, flags=re.M)]
    assert len(files) + len(refused) == len(fenced("toml")) and len(files) >= 2  # no block without a name
    for name, body in files.items():
        model = parse_model(body, name)
        assert model.states and len(model.dynamics) == model.n
    complete = parse_model(files["oscillator.toml"], "oscillator.toml")  # every table at once
    assert complete.parameters and complete.disturbances and complete.domain and "position" in complete.outputs


def test_every_command_states_its_exit_code_and_the_cheap_ones_are_the_pages() -> None:
    lines = command_lines()
    assert len(lines) >= 20
    for line in lines:
        stated(line)
    for wanted in CHEAP:
        assert sum(command(line) == wanted for line in lines) == 1, wanted


def test_the_cheap_commands_exit_as_the_page_says(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    for name, body in toml_files().items():
        (tmp_path / name).write_text(body)
    lines = command_lines()
    for wanted in CHEAP:
        line = next(line for line in lines if command(line) == wanted)
        args, code, note = stated(line)
        args = [str(ROOT / a) if a.startswith("examples/") else a for a in args]
        done = RUNNER.invoke(app.cli, args, env={"COLUMNS": "200"})
        assert done.exit_code == code, f"{line}\n{done.output}"
        verdict = note.split()[0] if note else ""
        if verdict in VERDICTS:
            again = RUNNER.invoke(app.cli, [*args, "--json"])
            assert json.loads(again.output)["verdict"] == verdict, line


def test_the_limits_on_the_page_are_the_codes() -> None:
    from lyapcheck import tolerances
    from lyapcheck.models.surfaces import certify
    from lyapcheck.models.language import expressions, modelfile
    from lyapcheck.models.classes import lyapunov

    assert (modelfile.MAX_STATES, modelfile.MAX_PARAMETERS, modelfile.MAX_DISTURBANCES) == (30, 64, 6)
    assert modelfile.MAX_FILE_BYTES == 256 * 1024
    assert (expressions.MAX_EXPONENT, expressions.MAX_TOTAL_DEGREE, expressions.MAX_TERMS) == (12, 12, 2000)
    assert (expressions.MAX_EXPRESSION_LENGTH, expressions.MAX_DEPTH) == (4000, 60)
    assert lyapunov.SOS_GAS_DEGREES == (2, 4, 6, 8) and lyapunov.MAX_GRAM_ROWS == 120
    assert tolerances.MODEL_CLASS_TIME_LIMIT_S == 60
    hard_stop = tolerances.MODEL_CLASS_TIME_LIMIT_S * certify.HARD_STOP_FACTOR + certify.HARD_STOP_GRACE_S
    assert hard_stop == 95 and tolerances.SIM_MAX_STEPS == 50_000
    assert certify.MODEL_CLASSES == ("linearization", "quadratic", "sos_gas", "roa", "candidate", "sos_bound",
                                     "barrier", "reach_avoid")
    for text in ("at most 30 (`MAX_STATES`)", "at most 64 (`MAX_PARAMETERS`)", "at most 6 (`MAX_DISTURBANCES`)",
                 "at most 12 (`MAX_EXPONENT`)", "`MODEL_CLASS_TIME_LIMIT_S` = 60 s", "1.5 x 60 + 5 = 95 s",
                 "`SIM_MAX_STEPS` = 50,000", "`linearization, quadratic, sos_gas, roa, candidate, sos_bound, barrier, reach_avoid`"):
        assert text in TEXT, text
