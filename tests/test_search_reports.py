"""Reports of the searches (issue 45, item 4): ``lyapcheck report`` of a ``tune --out`` certificate (the
box map with the winner and its certified neighbourhood, the objective along the search) and of a
``certify --maximize/--minimize --out`` certificate (the values tried with their outcomes, the answer);
a changed search table raises the page's alarm and fails ``verify``."""

from __future__ import annotations

import base64
import copy
import json
import math
import re
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.surfaces import extremum, tune
from reports.views import fmt_float
from tests.test_model_reports import Page, pdf_text

ROOT = Path(__file__).resolve().parents[1]
SCALAR = ROOT / "examples" / "models" / "linear-scalar-disturbed.toml"  # x' = -a x + d, |d| <= 1: limsup |x| = 1/a
OSCILLATOR = ROOT / "examples" / "models" / "damped-oscillator.toml"  # LES exactly when c > 0 and k > 0
app._register_commands()
RUNNER = CliRunner()
ALARM = "THE EXACT RE-CHECK FAILS"


@pytest.fixture(scope="module")
def tuned(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The quickest tune of tests/test_tune.py: the bound of the scalar loop, minimized over a in [1, 4]."""
    out = tmp_path_factory.mktemp("tune") / "tuned.json"
    done = RUNNER.invoke(app.cli, ["tune", str(SCALAR), "--box", "a=1..4", "--objective", "bound:y", "--grid", "2",
                                   "--out", str(out)])
    assert done.exit_code == 0, done.output
    doc: dict[str, Any] = json.loads(out.read_text())
    return doc


@pytest.fixture(scope="module")
def bisected(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """certify --minimize of the oscillator's damping (tests/test_extremum.py): 0.125 proved, 0 not."""
    out = tmp_path_factory.mktemp("extremum") / "smallest-c.json"
    done = RUNNER.invoke(app.cli, ["certify", str(OSCILLATOR), "--classes", "linearization", "--minimize", "c=-1..1",
                                   "--steps", "4", "--out", str(out)])
    assert done.exit_code == 0, done.output
    doc: dict[str, Any] = json.loads(out.read_text())
    return doc


def figure_svg(html: str, ident: str) -> str:
    """The SVG text of the page's figure ``ident`` (its base64 data URI)."""
    match = re.search(rf'<figure id="{ident}"[^>]*><img src="data:image/svg\+xml;base64,([^"]+)"', html)
    assert match, ident
    return base64.b64decode(match.group(1)).decode()


def page_of(doc: dict[str, Any]) -> tuple[str, Page]:
    from reports.render import certificate_html

    html = certificate_html(doc, simulate=False)
    return html, Page(html)


# -- tune ----------------------------------------------------------------------------------------------
def test_the_tune_report_shows_the_winner_its_neighbourhood_and_the_search(tuned: dict[str, Any],
                                                                           tmp_path: Path) -> None:
    path = tmp_path / "tuned.json"
    path.write_text(json.dumps(tuned))
    done = RUNNER.invoke(app.cli, ["report", str(path), "--html", str(tmp_path / "page.html"),
                                   "--pdf", str(tmp_path / "page.pdf")])
    assert done.exit_code == 0, done.output
    html = (tmp_path / "page.html").read_text()
    text = Page(html).text
    t = tuned["tune"]
    value = tune.weaker_float(Fraction(t["value_exact"]), "min")
    nb = t["neighbourhood"]
    lo, hi = nb["box"]["a"]
    assert t["point"] == {"a": "4"} and nb["certified"]
    assert f"winner: a = 4: the certified limsup |y - y_eq| (sos_bound) = {value:.6g}, certified again exactly" in text
    assert f"for every a in [{lo}, {hi}], the figure is <= {nb['value']:.6g}" in text
    assert t["value_exact"] in text  # the winner's figure, exactly
    assert ALARM not in text
    # every point tried, in order, and the winner marked
    rows = re.findall(r"<tr(?: class=\"winner\")?><td class=\"num\">(\d+)</td><td>(grid|refine)</td>",
                      html.split('id="tune-points"')[1].split("</table>")[0])
    assert [int(i) for i, _ in rows] == list(range(1, len(t["tried"]) + 1))
    assert [phase for _, phase in rows] == [p["phase"] for p in t["tried"]]
    winner_row = html.split('id="tune-points"')[1].split('class="winner"')[1].split("</tr>")[0]
    assert "<code>4</code>" in winner_row and fmt_float(value, 6) in winner_row
    # one parameter: a line plot with the winner, the neighbourhood's band and its proved figure
    svg = figure_svg(html, "fig-box-map")
    for gid in ("winner", "neighbourhood", "neighbourhood-figure", "search-box", "tried-grid", "tried-refine"):
        assert f'id="{gid}"' in svg, gid
    trace = figure_svg(html, "fig-objective")
    assert 'id="best-so-far"' in trace and 'id="winner"' in trace
    # the exact re-check runs the tune rows verify runs, and they hold
    recheck = html.split('<section id="recheck">')[1].split("</section>")[0]
    assert recheck.count("<code>tune</code>") == 4 and "fails" not in recheck
    ptext = pdf_text((tmp_path / "page.pdf").read_bytes())
    assert "The search (lyapcheck tune)" in ptext and "winner: a = 4" in ptext and f"a in [{lo}, {hi}]" in ptext


def _tampered(doc: dict[str, Any], change: Any) -> dict[str, Any]:
    out = copy.deepcopy(doc)
    change(out["tune"] if "tune" in out else out["extremum"])
    return out


def test_a_changed_tune_table_raises_the_alarm_and_fails_verify(tuned: dict[str, Any]) -> None:
    from lyapcheck.api import verify

    t = tuned["tune"]
    better = str(Fraction(t["value_exact"]) / 2)  # a bound twice as tight as was proved

    def claim_more(table: dict[str, Any]) -> None:
        table["value_exact"] = better

    def record_more(table: dict[str, Any]) -> None:  # a point tried that "beat" the winner
        loser = next(p for p in table["tried"] if p["point"] != table["point"])
        loser["value_exact"], loser["value"] = better, float(Fraction(better))

    def widen(table: dict[str, Any]) -> None:
        table["neighbourhood"]["box"]["a"][0] = "1"

    for change, said in ((claim_more, "the stated value is not the certificate's figure"),
                         (record_more, "a point tried has a better recorded figure than the winner's"),
                         (widen, "the neighbourhood's box is not its certificate's")):
        doc = _tampered(tuned, change)
        assert not verify(doc).valid
        _, page = page_of(doc)
        assert ALARM in page.text and "Do not trust this certificate" in page.text and said in page.text, said
    malformed = _tampered(tuned, lambda table: table.update(tried="not a list"))
    _, page = page_of(malformed)  # said in one line, never raised
    assert "the tune table is malformed" in page.text and ALARM in page.text


# -- certify --maximize / --minimize -------------------------------------------------------------------
def test_the_extremum_report_shows_every_value_tried_and_the_answer(bisected: dict[str, Any]) -> None:
    ext = bisected["extremum"]
    assert ext["proved"] == "0.125" and ext["failed"] == "0" and bisected["overrides"] == {"c": "0.125"}
    html, page = page_of(bisected)
    assert "c: the smallest value proved is 0.125; 0 was not proved" in page.text and ALARM not in page.text
    table = html.split('id="extremum-steps"')[1].split("</table>")[0]
    shown = re.findall(r"<td class=\"num\"><code>([^<]+)</code></td><td>(proved|refuted|not proved)", table)
    assert shown == [(s["value"], s["outcome"]) for s in ext["steps"]]
    assert {"refuted", "not proved", "proved"} <= {o for _, o in shown}
    svg = figure_svg(html, "fig-bisection")
    for gid in ("step-proved", "step-refuted", "step-not-proved", "proved", "failed", "gap"):
        assert f'id="{gid}"' in svg, gid
    recheck = html.split('<section id="recheck">')[1].split("</section>")[0]
    assert recheck.count("<code>extremum</code>") == 3 and "fails" not in recheck


def test_a_changed_extremum_table_raises_the_alarm_and_fails_verify(bisected: dict[str, Any]) -> None:
    from lyapcheck.api import verify

    def other_value(table: dict[str, Any]) -> None:  # a smaller damping than the certificate's
        table["proved"] = "0.0625"
        table["steps"].append({"value": "0.0625", "passed": True, "verdict": "certified_local", "outcome": "proved",
                               "seconds": 0.0})

    def hide_failure(table: dict[str, Any]) -> None:  # 0 "passed": the answer would be 0, not 0.125
        step = next(s for s in table["steps"] if s["value"] == "0")
        step.update(passed=True, outcome="proved", verdict="certified_local")

    for change, said in ((other_value, "the proved value is not the certificate's c"),
                         (hide_failure, "the proved value is not the best value that passed")):
        doc = _tampered(bisected, change)
        assert not verify(doc).valid
        _, page = page_of(doc)
        assert ALARM in page.text and said in page.text, said


@pytest.mark.parametrize("table", [[], "x", None, {"range": 5}, {"range": ["0", "1/0"]},
                                   {"range": ["0", "1"], "direction": "max", "parameter": "c", "steps": [[1]]}])
def test_a_malformed_search_table_fails_verify_in_one_row(tuned: dict[str, Any], bisected: dict[str, Any],
                                                          table: Any) -> None:
    """Any value where a table was: one failing row naming the table, never an exception (exit 3)."""
    from lyapcheck.api import verify

    for doc, key in ((tuned, "tune"), (bisected, "extremum")):
        result = verify({**doc, key: table})
        failed = [c for c in result.checks if not c.ok]
        assert not result.valid and failed[0].check == key and "malformed" in failed[0].message, failed


# -- the figures and the records, on their own ---------------------------------------------------------
def test_the_box_map_of_two_gains_marks_each_outcome_and_the_trace_keeps_the_best() -> None:
    from reports.search_figures import Tried, box_map, objective_trace

    tried = [Tried((0.5, 0.25), "grid", None, "refuted (unstable)"), Tried((0.5, 2.0), "grid", 3.0, "certified"),
             Tried((4.0, 0.25), "grid", 5.0, "certified"), Tried((4.0, 2.0), "grid", 2.0, "certified"),
             Tried((3.0, 2.0), "refine", None, "not_certified"), Tried((4.0, 1.5), "refine", 2.5, "certified")]
    drawn = box_map(["kp", "ki"], [(0.5, 4.0), (0.25, 2.0)], tried, 3, [(3.5, 4.0), (1.75, 2.0)],
                    [[(3.0, 4.0), (1.5, 2.0)]], label="bound:y (minimized)", sense="min", title="t")
    svg = drawn.svg.decode()
    for gid in ("winner", "neighbourhood", "neighbourhood-try-0", "search-box", "tried-grid", "tried-refine",
                "unproved-refuted", "unproved-other"):
        assert f'id="{gid}"' in svg, gid
    assert drawn.data["winner"] == [4.0, 2.0] and drawn.data["proved"] == 4 and not drawn.data["projected"]
    trace = objective_trace(tried, 3, label="bound:y", sense="min", title="t")
    best = trace.data["best_so_far"]
    assert math.isnan(best[0]) and best[1:] == [3.0, 3.0, 2.0, 2.0, 2.0]  # minimized: the smallest so far


def test_the_records_are_checked_for_what_a_search_would_have_made() -> None:
    good = extremum.Extremum("c", "max", Fraction(0), Fraction(1))
    for value, passed in ((1, False), (0, True), (Fraction(1, 2), True), (Fraction(3, 4), False)):
        good.steps.append(extremum.Step(Fraction(value), passed, "", "proved" if passed else "not proved", 0.0))
    good.proved, good.failed = Fraction(1, 2), good.steps[3]
    assert extremum.record_row(good)[1]
    again = extremum.Extremum.from_json(good.to_json())
    assert again.proved == good.proved and again.failed is not None and again.failed.value == Fraction(3, 4)
    assert extremum.record_row(again)[1]
    wrong = extremum.Extremum.from_json({**good.to_json(), "failed": "1"})  # 3/4 failed closer to the answer
    assert not extremum.record_row(wrong)[1]
    outside = extremum.Extremum.from_json({**good.to_json(), "range": ["0", "0.9"]})
    assert not extremum.record_row(outside)[1]


# -- the search's report straight from the command ---------------------------------------------------------
def test_tune_and_minimize_write_the_search_report_with_report(tmp_path: Path) -> None:
    """``tune --report`` and ``certify --minimize --report`` write the page ``lyapcheck report`` draws of
    the document ``--out`` writes; a report name that is neither .html nor .pdf is one line, exit 2."""
    page = tmp_path / "tune.html"
    done = RUNNER.invoke(app.cli, ["tune", str(SCALAR), "--box", "a=1..4", "--objective", "bound:y", "--grid", "2",
                                   "--report", str(page)])
    assert done.exit_code == 0, done.output
    assert f"report of the search written to {page}" in done.output
    text = Page(page.read_text()).text
    assert "winner: a = 4" in text and ALARM not in text
    page = tmp_path / "smallest-c.html"
    done = RUNNER.invoke(app.cli, ["certify", str(OSCILLATOR), "--classes", "linearization", "--minimize", "c=-1..1",
                                   "--steps", "4", "--report", str(page)])
    assert done.exit_code == 0, done.output
    text = Page(page.read_text()).text
    assert "c: the smallest value proved is 0.125; 0 was not proved" in text and ALARM not in text
    done = RUNNER.invoke(app.cli, ["tune", str(SCALAR), "--box", "a=1..4", "--objective", "bound:y",
                                   "--report", str(tmp_path / "page.txt")])
    assert done.exit_code == 2 and "'report' parameter" in done.output and "page.txt" in done.output
    assert len(done.output.strip().splitlines()) == 1
