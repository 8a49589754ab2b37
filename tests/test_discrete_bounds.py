"""``sos_bound`` on polynomial discrete-time maps (issue 44, "digital controllers"):
:mod:`lyapcheck.models.classes.discrete_bounds`.

What is asserted: on ``examples/models/discrete-disturbed-map.toml`` the class certifies a bound per output
that ``verify`` re-checks (exit 0), whose sentence speaks of iterates and steps and covers every disturbance
(``"all"``); the map iterated in floating point under random disturbance sequences within the bound (and the
extreme ones, ``d = +-b``) keeps each output eventually under its certified bound (independent of the class's
code); a certificate with its bound, ``V`` or ``lam`` changed fails ``verify`` (exit 1); maps the disturbance
drives without bound (an expanding and a marginal one) are never certified; a map without ``[disturbances]``
gets the continuous loop's ``not_applicable`` sentence; a negative bound is refused in one line (exit 2).
"""

from __future__ import annotations

import copy
import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.classes import discrete_bounds as db
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.search import Budget
from lyapcheck.models.language.modelfile import load_model
from lyapcheck.models.loop.discrete import shifted_map

app._register_commands()

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "models" / "discrete-disturbed-map.toml"


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    assert "Traceback" not in done.output
    return done


@pytest.fixture(scope="module")
def bounded(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any], int]:
    out = tmp_path_factory.mktemp("bound") / "bound.json"
    done = cli("certify", str(EXAMPLE), "--classes", "sos_bound", "--no-store", "--json", "--out", str(out))
    return out, json.loads(out.read_text()), done.exit_code


def _map(name: str, dynamics: str, tmp_path: Path, bound: str = "0.5") -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(f'[model]\nname = "{name}"\nstates = ["x"]\ntime = "discrete"\n\n[disturbances]\nd = {bound}\n\n'
                    f'[dynamics]\nx = "{dynamics}"\n\n[outputs]\nx = "x"\n')
    return path


def test_the_bound_certifies_and_verify_rechecks_it(bounded: tuple[Path, dict[str, Any], int]) -> None:
    path, doc, code = bounded
    assert code == 0
    c = doc["conditions"]["sos_bound"]
    assert c["status"] == "certified" and c["property"] == "ultimate_bound" and c["disturbances"] == "all"
    assert c["certificate"]["kind"] == db.KIND and c["certificate"]["time"] == "discrete"
    assert set(c["bounds"]) == {"x", "y"}
    assert "every iterate eventually stays within" in c["summary"] and "limsup over the steps" in c["summary"]
    for out, data in c["certificate"]["outputs"].items():
        assert 0 <= Fraction(data["lam"]) < 1
        assert Fraction(data["bound"]) ** 2 >= Fraction(data["B"])
        assert c["bounds"][out] >= float(Fraction(data["bound"])) * (1 - 1e-12)
    done = cli("verify", str(path))
    assert done.exit_code == 0, done.output
    assert "sos_bound: every output's step and output identities hold exactly" in done.output


def test_iterates_under_random_disturbances_stay_under_the_bound(bounded: tuple[Path, dict[str, Any], int]) -> None:
    bounds = bounded[1]["conditions"]["sos_bound"]["bounds"]
    rng = np.random.default_rng(11)
    starts = rng.uniform(-20, 20, size=(400, 2))
    x, y = starts[:, 0].copy(), starts[:, 1].copy()
    peak = {"x": 0.0, "y": 0.0}
    for step in range(400):
        kind = step // 100  # uniform, then bang-bang +-b, then constant +b, then uniform again
        d = (rng.uniform(-0.5, 0.5, size=len(x)) if kind in (0, 3) else
             0.5 * rng.choice([-1.0, 1.0], size=len(x)) if kind == 1 else np.full(len(x), 0.5))
        x, y = 0.5 * x + 0.1 * y ** 2, 0.6 * y + d
        if step >= 100:  # (from |y0| <= 20 both outputs have come within any margin of the bound by then)
            peak["x"] = max(peak["x"], float(np.max(np.abs(x))))
            peak["y"] = max(peak["y"], float(np.max(np.abs(y))))
    assert peak["x"] <= bounds["x"] and peak["y"] <= bounds["y"]
    # the bound says something: the constant disturbance drives y to 1.25 and x to 0.3125
    assert peak["y"] > 1.2 and peak["x"] > 0.3


def _tampered(folder: Path, doc: dict[str, Any], change: Any, name: str) -> Any:
    bad = copy.deepcopy(doc)
    change(bad["conditions"]["sos_bound"])
    path = folder / name
    path.write_text(json.dumps(bad))
    return cli("verify", str(path))


def test_a_tampered_certificate_fails_verify(bounded: tuple[Path, dict[str, Any], int], tmp_path: Path) -> None:
    doc = bounded[1]

    def bound_down(c: dict[str, Any]) -> None:  # the bound below sqrt(B), figure and certificate alike
        data = c["certificate"]["outputs"]["y"]
        data["bound"] = str(Fraction(data["bound"]) / 2)
        c["bounds"]["y"] = c["bounds"]["y"] / 2

    def figure_down(c: dict[str, Any]) -> None:  # the printed figure below the certified bound
        c["bounds"]["x"] = c["bounds"]["x"] * 0.9

    def v_shifted(c: dict[str, Any]) -> None:  # V + 1: the step identity is lost
        terms = c["certificate"]["outputs"]["x"]["V"]["terms"]
        zero = next((t for t in terms if not any(t[1])), None)
        if zero is None:
            terms.append(["1", [0, 0, 0]])
        else:
            zero[0] = str(Fraction(zero[0]) + 1)

    def lam_changed(c: dict[str, Any]) -> None:
        data = c["certificate"]["outputs"]["y"]
        data["lam"] = str(Fraction(data["lam"]) / 2)

    def lam_one(c: dict[str, Any]) -> None:  # lam = 1 proves no limsup
        c["certificate"]["outputs"]["y"]["lam"] = "1"

    for change in (bound_down, figure_down, v_shifted, lam_changed, lam_one):
        done = _tampered(tmp_path, doc, change, f"{change.__name__}.json")
        assert done.exit_code == 1, (change.__name__, done.output)
        assert "sos_bound" in done.output


@pytest.mark.parametrize("dynamics", ["1.1*x + d", "x + d"])
def test_a_map_the_disturbance_drives_without_bound_is_not_certified(dynamics: str, tmp_path: Path) -> None:
    model = load_model(_map("grows", dynamics, tmp_path))
    r = db.run(model, shifted_map(model), Budget(60, "test"))
    assert r.status == "not_certified", r.summary
    # (and the iterates do grow: a constant disturbance at its bound)
    x = 0.0
    for _ in range(200):
        x = (1.1 * x if dynamics.startswith("1.1") else x) + 0.5
    assert x > 50


def test_a_map_without_disturbances_gets_the_loops_sentence(tmp_path: Path) -> None:
    path = tmp_path / "calm.toml"
    path.write_text('[model]\nname = "calm"\nstates = ["x"]\ntime = "discrete"\n\n[dynamics]\nx = "0.5*x"\n\n'
                    '[outputs]\nx = "x"\n')
    out = tmp_path / "calm.json"
    cli("certify", str(path), "--classes", "sos_bound", "--no-store", "--json", "--out", str(out))
    c = json.loads(out.read_text())["conditions"]["sos_bound"]
    assert c["status"] == "not_applicable" and c["summary"] == reasons.NO_DISTURBANCES
    field = tmp_path / "field.toml"
    field.write_text('[model]\nname = "field"\nstates = ["x"]\n\n[dynamics]\nx = "-x"\n\n[outputs]\nx = "x"\n')
    out = tmp_path / "field.json"
    cli("certify", str(field), "--classes", "sos_bound", "--no-store", "--json", "--out", str(out))
    assert json.loads(out.read_text())["conditions"]["sos_bound"]["summary"] == c["summary"]


def test_a_negative_disturbance_bound_is_refused_in_one_line() -> None:
    done = cli("certify", str(EXAMPLE), "--classes", "sos_bound", "--no-store", "--set", "d=-1")
    assert done.exit_code == 2
    assert "d" in done.output and ">= 0" in done.output and "-1" in done.output
    assert len(done.output.strip().splitlines()) == 1


def test_the_maps_nominal_claims_beside_the_bound_verify_and_a_forged_coverage_does_not(tmp_path: Path) -> None:
    """With disturbances, a map's other classes are decided with them at 0 and say ``(d = 0)``; their exact checks
    compare the sentence without it (lyapcheck.models.classes.verify_discrete), and a claim restated for every
    disturbance fails."""
    out = tmp_path / "all.json"
    done = cli("certify", str(EXAMPLE), "--classes", "linearization,sos_gas,sos_bound", "--no-store", "--out", str(out))
    assert done.exit_code == 0, done.output
    doc = json.loads(out.read_text())
    gas = doc["conditions"]["sos_gas"]
    assert gas["status"] == "certified" and gas["disturbances"] == "zero" and gas["summary"].startswith("(d = 0) ")
    assert doc["conditions"]["sos_bound"]["disturbances"] == "all"
    assert cli("verify", str(out)).exit_code == 0
    bad = copy.deepcopy(doc)
    forged = bad["conditions"]["sos_gas"]
    forged["disturbances"] = "all"
    forged["summary"] = "for every disturbance signal within its bounds: " + forged["summary"][len("(d = 0) "):]
    path = tmp_path / "forged.json"
    path.write_text(json.dumps(bad))
    done = cli("verify", str(path))
    assert done.exit_code == 1 and "sos_gas" in done.output


def test_an_output_the_disturbance_cannot_bound_is_named_not_bounded(tmp_path: Path) -> None:
    """``x+ = x/2 + d`` is bounded (``|x|`` tends to at most ``b / (1 - 1/2) = 1``), ``y+ = y`` keeps any start: the
    claim bounds x alone, no smaller than the true limit, says "no bound for y", and verifies."""
    path = tmp_path / "partial.toml"
    path.write_text('[model]\nname = "partial"\nstates = ["x", "y"]\ntime = "discrete"\n\n[disturbances]\nd = 0.5\n\n'
                    '[dynamics]\nx = "0.5*x + d"\ny = "y"\n\n[outputs]\nx = "x"\ny = "y"\n')
    out = tmp_path / "partial.json"
    cli("certify", str(path), "--classes", "sos_bound", "--no-store", "--out", str(out))
    c = json.loads(out.read_text())["conditions"]["sos_bound"]
    assert c["status"] == "certified" and set(c["bounds"]) == {"x"} and "no bound for y" in c["summary"]
    x = 0.0
    for _ in range(200):  # d = +b at every step drives x to its limit 1
        x = 0.5 * x + 0.5
    assert x <= c["bounds"]["x"] and x > 0.99
    assert cli("verify", str(out)).exit_code == 0
