"""What if every loop took the classes of loops with functions? (issue 41, item 1: one implementation per class)

Each shipped polynomial or rational example is certified twice in one process, alternating: by its own
route (scaled polynomial identities, :mod:`lyapcheck.models.surfaces.certify`) and read as a loop with
functions that has no auxiliaries, so that the relational route runs on it
(:mod:`lyapcheck.models.classes.recast_regions`: the classes of :mod:`lyapcheck.models.classes.recast_classes`,
``recast_bound``, ``recast_barrier``, ``recast_reach_avoid``). It prints, per example, each route's time and
every class whose status or key figure differs. A certificate the relational route loses here is one
users would lose if that route became the only implementation of its class.

    python benchmarks/bench_route_whatif.py [--time-limit 30] [FILE.toml ...]

Without files: every ``examples/models/*.toml`` without functions, but the ones slower than a few minutes
per route (``lyznet-10d``, ``fossil-highord8``, ``paper-*``).
"""

from __future__ import annotations

import argparse
import time
import tomllib
from pathlib import Path
from typing import Any

from lyapcheck.models.language.modelfile import Model, _Reader, parse_any_model
from lyapcheck.models.surfaces.certify import certify_model

ROOT = Path(__file__).resolve().parents[1]
SKIPPED = ("lyznet-10d", "fossil-highord8", "paper-")
#: the figures compared (a level is not: the routes' V differ; the share of the simulated region is)
FIGURES = ("roa_share", "ball_radius", "decay_rate_per_s", "lambda_per_s", "reach_time_bound_s", "bounds")


def _figures(result: Any) -> dict[str, Any]:
    return {k: v for k, v in result.to_json().items() if k in FIGURES}


def _run(model: Any, limit: float) -> tuple[dict[str, tuple[str, dict[str, Any]]] | str, float]:
    from lyapcheck.models.engines import store

    start = time.perf_counter()
    try:
        with store.disabled():  # (no certificate kept from an earlier run: each route searches)
            found = certify_model(model, time_limit_s=limit)
        out: dict[str, tuple[str, dict[str, Any]]] | str = {k: (r.status, _figures(r)) for k, r in found.results.items()}
    except Exception as exc:  # noqa: BLE001 - a what-if: any failure of a route is a row of the table
        out = f"{type(exc).__name__}: {str(exc)[:120]}"
    return out, time.perf_counter() - start


def _short(value: Any) -> str:
    if isinstance(value, dict):
        return ", ".join(f"{k} {_short(v)}" for k, v in value.items())
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def compare(path: Path, limit: float) -> str:
    text = path.read_text()
    polynomial = parse_any_model(text, str(path))
    if not isinstance(polynomial, Model):
        return f"| {path.stem} | (a loop with functions: skipped) | | |"
    try:  # the same file read as a loop with functions (no auxiliaries)
        relational = _Reader(str(path), text, tomllib.loads(text), {}).recast_model(None)
    except Exception as exc:  # noqa: BLE001
        return f"| {path.stem} | | | not readable as a loop with functions: {str(exc)[-80:]} |"
    own, own_s = _run(polynomial, limit)
    other, other_s = _run(relational, limit)
    if isinstance(own, str) or isinstance(other, str):
        return f"| {path.stem} | {own_s:.1f} | {other_s:.1f} | {own if isinstance(own, str) else other} |"
    changes = []
    for name, (status, figures) in own.items():
        status2, figures2 = other.get(name, ("absent", {}))
        if status != status2:
            changes.append(f"{name}: {status} -> {status2}")
        elif status == "certified":
            changes += [f"{name} {k}: {_short(figures.get(k))} -> {_short(figures2.get(k))}"
                        for k in FIGURES if figures.get(k) != figures2.get(k)]
    return f"| {path.stem} | {own_s:.1f} | {other_s:.1f} | {'; '.join(changes) or 'the same'} |"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", type=Path)
    parser.add_argument("--time-limit", type=float, default=30.0, help="each class's limit, s (default 30)")
    args = parser.parse_args()
    files = args.files or [p for p in sorted((ROOT / "examples" / "models").glob("*.toml"))
                           if not p.stem.startswith("recast-") and not p.stem.startswith(SKIPPED)]
    print("| example | own route, s | relational route, s | what changes on the relational route |")
    print("|---|---|---|---|")
    for path in files:
        print(compare(path, args.time_limit), flush=True)


if __name__ == "__main__":
    main()
