"""A disturbance of bound 0 (``--set d=0``, ``d = 0`` in the file or in ``[sweep.set]``) is identically 0.

It used to crash ``barrier`` (exit 3: "expected 4 exponents, got 3" in the rounding): the barrier's robust
field drops every disturbance of bound 0 (or one that enters nothing) from its ring, while its search rounded
in the scaled ring that keeps them all; ``reach_avoid`` had the same mismatch. ``sos_bound`` kept the
disturbance in its program, where only ``tau (0 - d^2)`` could hold its terms, and found nothing. Now the
scaled field sets such a disturbance to 0 (:func:`lyapcheck.models.loop.field.apply_scaling`), each safety
class rounds in its own field's ring (:meth:`lyapcheck.models.engines.search.Search.over`), and a claim
proved at d = 0 covers ``"all"`` where every bound is 0. Every answer here is re-checked by ``verify``.
"""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner, Result

from lyapcheck.cli import app

app._register_commands()

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "models"
TUBE = EXAMPLES / "disturbed-tube.toml"
#: the tube's goal, for reach_avoid: the invariant disks of radius >= 0.1414 hold every trajectory
GOAL = '\ngoal = ["x**2 + y**2 <= 0.25"]\n'


def run_cli(*args: str) -> Result:
    return CliRunner().invoke(app.cli, list(args))


def certified_and_verified(tmp_path: Path, model: Path, *args: str) -> dict[str, Any]:
    """``certify MODEL ARGS --json --out``: a proper answer (exit 0 or 1, never 3), and ``verify`` accepts
    the certificate; the conditions."""
    out = tmp_path / "cert.json"
    result = run_cli("certify", str(model), *args, "--json", "--out", str(out))
    assert result.exit_code in (0, 1), result.output
    conditions: dict[str, Any] = json.loads(result.stdout)["conditions"]
    checked = run_cli("verify", str(out))
    assert checked.exit_code == 0, checked.output
    return conditions


def tube_with_goal(tmp_path: Path, text: str | None = None) -> Path:
    path = tmp_path / "tube-goal.toml"
    path.write_text((TUBE.read_text() if text is None else text) + GOAL)
    return path


@pytest.mark.parametrize("zero", [("d1",), ("d2",), ("d1", "d2")])
def test_barrier_and_reach_avoid_with_a_zero_bound_are_certified_and_verify(tmp_path: Path, zero: tuple[str, ...]
                                                                            ) -> None:
    """The reported crash (``--classes barrier --set d1=0`` exited 3) and its twin in reach_avoid."""
    settings = [a for d in zero for a in ("--set", f"{d}=0")]
    conditions = certified_and_verified(tmp_path, tube_with_goal(tmp_path), *settings,
                                        "--classes", "barrier,reach_avoid")
    for name in ("barrier", "reach_avoid"):
        assert conditions[name]["status"] == "certified", conditions[name]
        assert conditions[name]["disturbances"] == "all"


def test_a_declared_disturbance_that_enters_nothing_leaves_barrier_its_ring(tmp_path: Path) -> None:
    """Same mismatch with a bound > 0: a disturbance that no right-hand side uses is not in the robust
    field's ring either (this too exited 3)."""
    text = TUBE.read_text().replace('x = "-x + y + d1"', 'x = "-x + y"').replace('y = "-x - y + d2"', 'y = "-x - y"')
    conditions = certified_and_verified(tmp_path, tube_with_goal(tmp_path, text), "--classes",
                                        "barrier,reach_avoid,quadratic")
    assert all(conditions[name]["status"] == "certified" for name in ("barrier", "reach_avoid", "quadratic"))
    assert {c["disturbances"] for c in conditions.values()} == {"all"}


def test_the_scaled_field_holds_no_disturbance_of_bound_zero() -> None:
    """d1 = 0 leaves no term in d1 in the scaled field (its variable stays in the ring, for the certificate
    formats), while d2 keeps its terms; with the bound raised again d1 is back."""
    from lyapcheck.api import load_model_file
    from lyapcheck.models.loop.field import active_disturbances, apply_scaling, choose_scaling, clear, shifted_field

    for settings, kept in ((["d1=0"], {1}), (["d1=0", "d2=0"], set()), ([], {0, 1})):
        model = load_model_file(TUBE, settings)
        shifted = shifted_field(model)
        cleared = clear(shifted, [])
        scaled = apply_scaling(cleared, choose_scaling(cleared))
        ring = scaled.ring
        used = {k for p in (*scaled.g, scaled.D) for m in ring.support(p) for k in range(2) if m[scaled.n + k]}
        assert used == kept, settings
        assert set(active_disturbances(scaled)) == kept
        assert ring.nvars == scaled.n + 2


def test_sos_bound_with_a_zero_bound_is_certified(tmp_path: Path) -> None:
    """With d1 = 0 the bound on x is proved again (before: not_certified, the solver's points refused), and
    it is no larger than with both disturbances acting (the same search on a smaller set of signals)."""
    both = certified_and_verified(tmp_path, TUBE, "--classes", "sos_bound")["sos_bound"]
    one = certified_and_verified(tmp_path, TUBE, "--set", "d1=0", "--classes", "sos_bound")["sos_bound"]
    assert both["status"] == one["status"] == "certified"
    assert one["disturbances"] == "all"
    for name in ("x", "y"):
        assert one["bounds"][name] <= both["bounds"][name] * (1 + 1e-9)


def test_a_bound_zero_in_the_file_answers_as_set_zero_and_every_claim_covers_all(tmp_path: Path) -> None:
    """``d1 = 0`` and ``d2 = 0`` written in the file: the same answers as ``--set``, and since each
    disturbance is identically 0, every claim (the linearization's too) holds for every admissible signal."""
    path = tmp_path / "tube-zero.toml"
    path.write_text(TUBE.read_text().replace("d1 = 0.1", "d1 = 0").replace("d2 = 0.1", "d2 = 0"))
    classes = "linearization,quadratic,sos_bound,barrier"
    written = certified_and_verified(tmp_path, path, "--classes", classes)
    assert {name: c["status"] for name, c in written.items()} == dict.fromkeys(classes.split(","), "certified")
    assert {c["disturbances"] for c in written.values()} == {"all"}
    assert not any(c["summary"].startswith("(d = 0)") for c in written.values())
    flags = certified_and_verified(tmp_path, TUBE, "--set", "d1=0", "--set", "d2=0", "--classes", classes)
    assert {n: (c["status"], c["disturbances"]) for n, c in flags.items()} == \
        {n: (c["status"], c["disturbances"]) for n, c in written.items()}
    # one bound left > 0: the linearization is again the nominal loop's claim only
    one = certified_and_verified(tmp_path, TUBE, "--set", "d1=0", "--classes", "linearization")
    assert one["linearization"]["disturbances"] == "zero"


def test_a_box_of_a_parameter_with_a_zero_disturbance(tmp_path: Path) -> None:
    """``--box`` of a parameter the disturbance does not touch, with d = 0: every claim holds over the box
    for the (only) disturbance d = 0."""
    conditions = certified_and_verified(tmp_path, EXAMPLES / "linear-scalar-disturbed.toml", "--box", "a=1..3",
                                        "--set", "d=0", "--classes", "linearization,quadratic,sos_bound")
    assert {c["status"] for c in conditions.values()} == {"certified"}
    assert {c["disturbances"] for c in conditions.values()} == {"all"}


def test_a_loop_with_functions_at_a_zero_bound_claims_all(tmp_path: Path) -> None:
    """The pendulum under a torque of bound 0: recast with d = 0, which is then every admissible d."""
    conditions = certified_and_verified(tmp_path, EXAMPLES / "recast-pendulum-torque.toml", "--set", "d=0",
                                        "--classes", "linearization,sos_bound")
    assert {c["status"] for c in conditions.values()} == {"certified"}
    assert {c["disturbances"] for c in conditions.values()} == {"all"}
    assert not conditions["linearization"]["summary"].startswith("(d = 0)")


def test_a_sweep_with_zero_bounds_in_sweep_set(tmp_path: Path) -> None:
    """``[sweep.set]`` with both bounds 0, over the wall's position: barrier and sos_bound at every point,
    each point's certificate verified (a barrier at any point used to exit 3)."""
    import numpy as np
    import zarr

    from lyapcheck.api import sweep, verify

    model = tmp_path / "tube.toml"
    model.write_text(TUBE.read_text().replace("[disturbances]", "[parameters]\nw = 1.25\n\n[disturbances]")
                     .replace('unsafe = ["1.25 <= x"]', 'unsafe = ["w <= x"]'))
    spec = tmp_path / "spec.toml"
    spec.write_text('[sweep]\nmodel = "tube.toml"\nmode = "points"\nclasses = ["barrier", "sos_bound"]\n'
                    '[[sweep.axes]]\nname = "w"\nvalues = [1.15, 1.25]\n[sweep.set]\nd1 = 0\nd2 = 0\n'
                    '[simulation]\nstarts = 2\nseed = 0\n')
    result = sweep(spec, tmp_path / "out.zarr", workers=0)
    assert result.summary.computed == 2
    group: Any = zarr.open_group(str(tmp_path / "out.zarr"), mode="r")
    assert np.all(np.asarray(group["status_barrier"][...]) == 1)  # 1: certified
    assert np.all(np.asarray(group["status_sos_bound"][...]) == 1)
    for cert in np.asarray(group["certificate"][...]):
        doc = json.loads(str(cert))
        assert Fraction(doc["disturbances"]["d1"]) == 0
        assert verify(doc).valid


def test_maximize_a_disturbance_bound_from_zero() -> None:
    """``--maximize d1=0..3`` certifies its low end, d1 = 0 (this exited 3 after the high end was refuted);
    the two ends only (``steps=0``): 3 is unsafe (a simulated trajectory enters the wall), 0 is proved."""
    from lyapcheck.api import certify_extremum, verify

    found = certify_extremum(TUBE, "d1=0..3", steps=0, classes="barrier")
    assert [(s.value, s.outcome) for s in found.steps] == [(3, "refuted"), (0, "proved")]
    assert found.proved == 0 and found.proved_result.conditions["barrier"].status == "certified"
    assert verify(found.proved_result).valid
