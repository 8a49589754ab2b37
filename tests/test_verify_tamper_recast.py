"""``verify`` re-derives every claim a certificate prints, on loops with functions (issue 40, item 6).

Each edit below of a certificate document (the property of a condition, a GES constant, a decay rate,
a level, a bound, the candidate text, the order of the states, a sentence) changes what a reader is
told without changing the proof; each must be refused by the check that names it, as on polynomial
loops. Each loop is certified once per module (cheap classes), and the edits are made on copies.
"""

from __future__ import annotations

import copy
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable

import pytest

from lyapcheck import api
from tests.recast_loops import COUPLED

MODELS = Path(__file__).resolve().parent.parent / "examples" / "models"

#: GES needs a field without denominators; no shipped loop with functions has both that and a
#: quadratic V: COUPLED (tests/recast_loops.py; tests/test_recast_classes.py proves its bound on simulations)
#: a candidate whose sublevel set ball arithmetic proves on the true pendulum (examples/models/README.md)
PENDULUM_V = "1 - cos(theta) + omega**2/2 + theta*omega/4"

Doc = dict[str, Any]


def certified(model: str | Path, classes: str, candidate: str | None = None) -> Doc:
    return api.certify(model=str(model), classes=classes, candidate=candidate).to_json()


@pytest.fixture(scope="module")
def ilos() -> Doc:
    """GAS with a denominator (the square root), by quadratic and sos_gas; LES."""
    return certified(MODELS / "recast-ilos-course.toml", "linearization,quadratic,sos_gas")


@pytest.fixture(scope="module")
def ges(tmp_path_factory: pytest.TempPathFactory) -> Doc:
    path = tmp_path_factory.mktemp("ges") / "coupled.toml"
    path.write_text(COUPLED)
    return certified(path, "quadratic")


@pytest.fixture(scope="module")
def bound() -> Doc:
    return certified(MODELS / "recast-ilos-course-disturbed.toml", "sos_bound")


@pytest.fixture(scope="module")
def region() -> Doc:
    """A region of attraction by ball arithmetic (an ``interval`` certificate) of the user's V."""
    return certified(MODELS / "recast-pendulum.toml", "candidate", PENDULUM_V)


@pytest.fixture(scope="module")
def global_candidate() -> Doc:
    """The user's V proves GAS on the recasting's relations (a ``recast`` certificate)."""
    return certified(MODELS / "recast-ilos-course.toml", "candidate", "2*y**2 + y*yi + yi**2")


@pytest.fixture(scope="module")
def unstable() -> Doc:
    """Refutations: the linearization (unstable) and sos_gas (another equilibrium)."""
    return certified(MODELS / "recast-unstable-pendulum.toml", "linearization,sos_gas")


@pytest.fixture(scope="module")
def oscillator() -> Doc:
    """A polynomial loop."""
    return certified(MODELS / "damped-oscillator.toml", "linearization,quadratic")


DOCS = ("ilos", "ges", "bound", "region", "global_candidate", "unstable", "oscillator")


def edited(doc: Doc, edit: Callable[[Doc], Any]) -> Doc:
    out = copy.deepcopy(doc)
    edit(out)
    return out


def assert_refused(doc: Doc, check: str, words: str) -> None:
    """verify refuses the document, and the failing row ``check`` says ``words``."""
    result = api.verify(doc)
    failed = [(c.check, c.message) for c in result.checks if not c.ok]
    assert not result.valid
    assert any(name == check and words in message for name, message in failed), failed


def test_the_documents_as_certified_verify(request: pytest.FixtureRequest) -> None:
    expected = {"ilos": ("linearization", "quadratic", "sos_gas"), "ges": ("quadratic",), "bound": ("sos_bound",),
                "region": ("candidate",), "global_candidate": ("candidate",), "unstable": ("linearization", "sos_gas")}
    for name in DOCS:
        doc = request.getfixturevalue(name)
        result = api.verify(doc)
        assert result.valid, (name, [c for c in result.checks if not c.ok])
        rows: dict[str, list[str]] = {}
        for c in result.checks:  # (a candidate has two rows: its proof and its text)
            rows.setdefault(c.check, []).append(c.message)
        assert rows["states"] == ["the states, in order, and the model's name are the model text's"]
        for condition in expected.get(name, ()):
            decided = doc["conditions"][condition]["status"]
            assert decided in ("certified", "refuted"), (name, condition, decided)
            assert any("property and figures as proved" in m for m in rows[condition]), (name, condition)
    assert request.getfixturevalue("ges")["conditions"]["quadratic"]["property"] == "GES"


@pytest.mark.parametrize(("fixture", "condition", "claimed"), [
    ("region", "candidate", "GAS"),          # ROA -> GAS
    ("ilos", "sos_gas", "GES"),              # GAS -> GES
    ("ilos", "quadratic", "GES"),
    ("global_candidate", "candidate", "GES"),
    ("bound", "sos_bound", "GAS"),           # ultimate_bound -> GAS
    ("ilos", "linearization", "GES"),        # LES -> GES
    ("unstable", "sos_gas", "GES"),          # a refutation of GAS stated as one of GES
])
def test_a_changed_property_is_refused(request: pytest.FixtureRequest, fixture: str, condition: str,
                                       claimed: str) -> None:
    doc = request.getfixturevalue(fixture)
    assert_refused(edited(doc, lambda d: d["conditions"][condition].update(property=claimed)), condition,
                   f"the stated property '{claimed}'")


def test_a_halved_ges_constant_is_refused(ges: Doc) -> None:
    quadratic = ges["conditions"]["quadratic"]
    k = Fraction(quadratic["certificate"]["k"])
    assert quadratic["k"] == float(k)
    # the figure beside the status
    assert_refused(edited(ges, lambda d: d["conditions"]["quadratic"].update(k=float(k / 2))), "quadratic",
                   "the stated figure 'k'")
    # the sentence
    exact = f"|x(t)| <= {float(k):.4g} |x0|"
    assert exact in quadratic["summary"]

    def in_sentence(d: Doc) -> None:
        d["conditions"]["quadratic"]["summary"] = quadratic["summary"].replace(exact, f"|x(t)| <= {float(k / 2):.4g} |x0|")

    assert_refused(edited(ges, in_sentence), "quadratic", "printed sentence")

    # the figure, the certificate's k and the sentence together: k no longer follows from c1, c2
    def everywhere(d: Doc) -> None:
        c = d["conditions"]["quadratic"]
        c["certificate"]["k"] = str(k / 2)
        c["k"] = float(k / 2)
        c["summary"] = c["summary"].replace(exact, f"|x(t)| <= {float(k / 2):.4g} |x0|")

    assert_refused(edited(ges, everywhere), "quadratic", "k is below sqrt(c2/c1)")


def test_a_raised_decay_rate_or_level_is_refused(ges: Doc, region: Doc) -> None:
    rate = ges["conditions"]["quadratic"]["decay_rate_per_s"]
    assert_refused(edited(ges, lambda d: d["conditions"]["quadratic"].update(decay_rate_per_s=rate * 10)),
                   "quadratic", "the stated figure 'decay_rate_per_s'")
    level = region["conditions"]["candidate"]["level"]
    assert_refused(edited(region, lambda d: d["conditions"]["candidate"].update(level=level * 2)), "candidate",
                   "the stated figure 'level'")


@pytest.mark.parametrize(("fixture", "condition", "figure"), [
    ("ilos", "sos_gas", "level"),                  # a region's figure beside a global claim
    ("ilos", "quadratic", "decay_rate_per_s"),     # a rate of |x| where the class proves none (GAS)
    ("ges", "quadratic", "level"),
    ("region", "candidate", "decay_rate_V_per_s"),
    ("ilos", "quadratic", "k"),                    # a GES constant beside a GAS claim
    ("region", "candidate", "ball_radius"),
    ("bound", "sos_bound", "level"),
])
def test_an_invented_figure_is_refused(request: pytest.FixtureRequest, fixture: str, condition: str,
                                       figure: str) -> None:
    doc = request.getfixturevalue(fixture)
    assert figure not in doc["conditions"][condition]
    assert_refused(edited(doc, lambda d: d["conditions"][condition].update({figure: 0.523})), condition,
                   f"the figure '{figure}' is not one this certificate proves")


def test_a_changed_bound_or_reference_is_refused(bound: Doc) -> None:
    figures = bound["conditions"]["sos_bound"]
    output = next(iter(figures["bounds"]))
    smaller = {**figures["bounds"], output: figures["bounds"][output] / 2}
    assert_refused(edited(bound, lambda d: d["conditions"]["sos_bound"].update(bounds=smaller)), "sos_bound",
                   "the stated figure 'bounds'")
    moved = {**figures["bounds_reference"], output: figures["bounds_reference"][output] + 1}
    assert_refused(edited(bound, lambda d: d["conditions"]["sos_bound"].update(bounds_reference=moved)),
                   "sos_bound", "the stated figure 'bounds_reference'")


def test_the_candidate_text_is_the_certified_v(global_candidate: Doc, region: Doc) -> None:
    other = edited(global_candidate, lambda d: d.update(candidate="3*y**2 + y*yi + yi**2"))
    assert_refused(other, "candidate", "not the V of the certified candidate condition")
    assert_refused(edited(global_candidate, lambda d: d.update(candidate=None)), "candidate",
                   "needs the candidate text")
    assert_refused(edited(region, lambda d: d.update(candidate=PENDULUM_V.replace("/4", "/5"))), "candidate",
                   "not the V of the certified candidate condition")
    assert_refused(edited(region, lambda d: d.update(candidate="theta +")), "model", "--candidate")


@pytest.mark.parametrize("fixture", ["ilos", "region", "bound", "oscillator"])
def test_a_swapped_state_order_or_another_name_is_refused(request: pytest.FixtureRequest, fixture: str) -> None:
    doc = request.getfixturevalue(fixture)
    assert len(doc["states"]) == 2
    assert_refused(edited(doc, lambda d: d.update(states=d["states"][::-1])), "states", "the stated order")
    assert_refused(edited(doc, lambda d: d["model"].update(name="another loop")), "states",
                   "the stated model name")


def test_the_sentences_of_the_linearization_and_of_a_refutation_are_re_derived(unstable: Doc, ilos: Doc) -> None:
    certified_text = ilos["conditions"]["linearization"]["summary"]
    assert_refused(edited(unstable, lambda d: d["conditions"]["linearization"].update(summary=certified_text)),
                   "linearization", "printed sentence")
    refuted = unstable["conditions"]["sos_gas"]["summary"]
    point = next(iter(unstable["conditions"]["sos_gas"]["refutation"]["point"].values()))
    assert point in refuted
    assert_refused(edited(unstable, lambda d: d["conditions"]["sos_gas"].update(
        summary=refuted.replace(point, "1/2*pi"))), "sos_gas", "printed sentence")


def test_simulation_estimates_are_left_as_stated_and_named(region: Doc) -> None:
    """A share from simulation claims nothing and is not re-derived (it would take the simulation);
    verify says which figures it left as stated, and refuses a figure it does not know."""
    share = region["conditions"]["candidate"]["simulated_roa_share_of_box"]
    assert 0 < share < 1
    doc = edited(region, lambda d: d["conditions"]["candidate"].update(simulated_roa_share_of_box=1.0))
    result = api.verify(doc)
    assert result.valid
    row = next(c.message for c in result.checks if c.check == "candidate")
    assert "left as stated, estimates that claim nothing: " in row and "simulated_roa_share_of_box" in row
    assert_refused(edited(region, lambda d: d["conditions"]["candidate"].update(roa_share_proved=1.0)),
                   "candidate", "the figure 'roa_share_proved'")


@pytest.mark.parametrize(("condition", "edit", "words"), [
    ("linearization", {"property": "GES"}, "the stated property 'GES'"),
    ("linearization", {"decay_rate_per_s": 3.0}, "the figure 'decay_rate_per_s'"),
    ("quadratic", {"ball_radius": 0.5}, "the figure 'ball_radius'"),
    ("quadratic", {"degree": 4}, "the stated figure 'degree'"),
])
def test_on_a_polynomial_loop_the_same_rule_holds(oscillator: Doc, condition: str, edit: dict[str, Any],
                                                  words: str) -> None:
    assert oscillator["conditions"]["quadratic"]["property"] == "GES"
    assert_refused(edited(oscillator, lambda d: d["conditions"][condition].update(edit)), condition, words)
