"""``quadratic`` and ``sos_gas`` on a loop with functions: the polynomial loops' implementation
(:mod:`lyapcheck.models.classes.lyapunov`) with the recasting's relations, its certificate kind
``lyapunov_relations`` re-checked exactly by verify, and the older kind refused in one line."""

from __future__ import annotations

import copy
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable

import pytest

from lyapcheck import api
from lyapcheck.models.classes import lyapunov
from tests.conftest import ROOT
from tests.recast_loops import COUPLED

Doc = dict[str, Any]
MODELS = ROOT / "examples" / "models"


@pytest.fixture(scope="module")
def ilos() -> Any:
    """GAS with a denominator (the square root): quadratic and sos_gas, each with its relations' multipliers."""
    return api.certify(model=str(MODELS / "recast-ilos-course.toml"), classes="quadratic,sos_gas")


@pytest.fixture(scope="module")
def coupled(tmp_path_factory: pytest.TempPathFactory) -> Any:
    path = tmp_path_factory.mktemp("coupled") / "coupled.toml"
    path.write_text(COUPLED)
    return api.certify(model=str(path), classes="quadratic")


def refused_rows(doc: Doc, name: str) -> list[str]:
    report = api.verify(doc)
    assert not report.valid
    return [c.message for c in report.checks if not c.ok and c.check == name]


def test_the_certificates_are_of_the_new_kind_and_verify(ilos: Any, coupled: Any) -> None:
    for result, names in ((ilos, ("quadratic", "sos_gas")), (coupled, ("quadratic",))):
        for name in names:
            c = result.conditions[name]
            assert c.status == "certified" and c.certificate["kind"] == lyapunov.RELATIONS_KIND
        assert api.verify(result).valid
    # the recasting's relations carry the coupled loop's proof (sin and tanh bounded by their arguments)
    decrease = coupled.conditions["quadratic"].certificate["decrease"]
    assert any(p["terms"] for p in decrease["lambdas"].values()) or decrease["taus"]
    # a square root's denominator is proved positive for ILOS
    assert ilos.conditions["quadratic"].certificate["recasting"]["denominators"]
    assert coupled.conditions["quadratic"].property == "GES"


def _scaled_gram(key: str) -> Callable[[Doc], None]:
    def edit(cert: Doc) -> None:
        gram = cert[key]
        gram["Q"] = [[str(Fraction(x) * 2) for x in row] for row in gram["Q"]]
    return edit


def _first_multiplier(cert: Doc) -> None:
    """One more term in the first relation's multiplier: ``-1 h_i`` more in the identity."""
    decrease = cert["decrease"]
    nv = len(cert["variables"])
    if decrease["lambdas"]:
        decrease["lambdas"][next(iter(decrease["lambdas"]))]["terms"].append(["1", [0] * nv])
    else:
        tau = decrease["taus"][next(iter(decrease["taus"]))]
        tau["Q"][0][0] = str(Fraction(tau["Q"][0][0]) + 1)


@pytest.mark.parametrize("tamper", ["gram_V", "sigma", "multiplier", "mu", "v_variables", "denominator", "degree"])
def test_a_tampered_certificate_of_the_new_kind_fails_verify(ilos: Any, tamper: str) -> None:
    doc = copy.deepcopy(ilos.document)
    cert = doc["conditions"]["sos_gas"]["certificate"]
    if tamper == "gram_V":
        _scaled_gram("gram_V")(cert)
    elif tamper == "sigma":
        _scaled_gram("sigma")(cert["decrease"])
    elif tamper == "multiplier":
        _first_multiplier(cert)
    elif tamper == "mu":
        cert["mu"] = "1/2"
    elif tamper == "v_variables":
        cert["v_variables"] = cert["v_variables"][:1]
    elif tamper == "denominator":
        cert["recasting"]["denominators"] = []
    else:
        cert["degree"] = 4
    assert refused_rows(doc, "sos_gas"), tamper


def test_a_larger_k_claim_than_proved_fails_verify(coupled: Any) -> None:
    for key, factor in (("k", Fraction(1, 2)), ("c1", Fraction(3)), ("mu", Fraction(2))):
        doc = copy.deepcopy(coupled.document)
        cert = doc["conditions"]["quadratic"]["certificate"]
        cert[key] = str(Fraction(cert[key]) * factor)
        assert refused_rows(doc, "quadratic"), key


def test_a_certificate_of_the_older_relational_format_is_refused_in_one_line(ilos: Any) -> None:
    doc = copy.deepcopy(ilos.document)
    for name in ("quadratic", "sos_gas"):
        doc["conditions"][name]["certificate"]["kind"] = "recast"
    for name in ("quadratic", "sos_gas"):
        refused = refused_rows(doc, name)
        assert refused == [f"{name}: {lyapunov.OLD_FORMAT}"]  # (and the verdict and exit code follow from it)
        assert "run lyapcheck certify again" in refused[0] and "\n" not in refused[0]
