"""Worst-case disturbance search at the paper's gains: time, the figures, and the tightness ratio.

    python benchmarks/bench_worst_case.py [--preset paper-ilos] [--budget 20] [--seed 0] [--no-storage]

Workload: :func:`lyapcheck.paper.simulation.worst_case.search_worst_case` on the preset (the paper's
gains, 100 s, tail 10 s, from ``p(0) = (0, -40 mm)`` and from the origin), with the ``sos_bound``
storage certificate for the ``storage_gradient`` family (its SDP search is timed separately and
is not part of the search's time). Prints the best tail sup of ``|eps|`` per family, the
overall worst, the search's rounds and wall time, and ``certified / worst`` for the
``sos_bound`` bound (the goal at the paper's gains: at most 1.5). Everything is measured in
this one run.
"""

from __future__ import annotations

import argparse
import json
import time
from fractions import Fraction

from lyapcheck.paper.simulation.scenarios import PRESETS, preset
from lyapcheck.paper.simulation.worst_case import FAMILIES, search_worst_case, storage_certificate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default="paper-ilos", choices=PRESETS)
    parser.add_argument("--budget", type=float, default=20.0, help="wall-time budget of the search, s")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--no-storage", action="store_true", help="skip the sos_bound certificate")
    parser.add_argument("--json", action="store_true", help="print the full result as JSON at the end")
    args = parser.parse_args()

    scenario = preset(args.preset)
    storage = None
    certified = None
    if not args.no_storage and scenario.controller == "ilos":
        t0 = time.perf_counter()
        storage = storage_certificate(scenario.problem)
        t_cert = time.perf_counter() - t0
        if storage is not None:
            certified = float(Fraction(storage["eps_bound"]))
            print(f"sos_bound certificate: limsup |eps| <= {certified * 1e3:.4f} mm ({t_cert:.1f} s, not in the search time)")
        else:
            print(f"sos_bound: no certificate ({t_cert:.1f} s)")

    t0 = time.perf_counter()
    result = search_worst_case(scenario, budget_s=args.budget, seed=args.seed, storage=storage)
    elapsed = time.perf_counter() - t0

    print(f"\nworst-case search, {args.preset}, d* = {result.d_max_m_s * 1e3:.4g} mm/s, "
          f"horizon {result.horizon_s:g} s, tail {result.tail_s:g} s")
    print(f"{'family':<18} {'sup|eps| tail (mm)':>19} {'start':>8} {'rtol':>7}  disturbance")
    for fam in FAMILIES:
        f = result.per_family[fam]
        if f is None:
            print(f"{fam:<18} {'-':>19} {'':>8} {'':>7}  ({result.skipped.get(fam, '')})")
            continue
        d = f.disturbance
        what = d["kind"]
        if "angular_frequency_rad_s" in d:
            what += f", omega = {d['angular_frequency_rad_s']:.4f} rad/s, phase = {d['phase_rad']:.3f} rad"
        elif d["kind"] == "bang_bang":
            what += f", {len(d['switch_times_s'])} switches"
        elif d["kind"] == "constant":
            what += f", velocity = ({d['velocity_m_s'][0] * 1e3:.4g}, {d['velocity_m_s'][1] * 1e3:.4g}) mm/s"
        print(f"{fam:<18} {f.sup_abs_eps_tail_m * 1e3:>19.5f} {f.start:>8} {f.rtol:>7.0e}  {what}")
    print("\nper initial state: " + ", ".join(f"{k} {v.sup_abs_eps_tail_m * 1e3:.5f} mm ({v.disturbance['family']})"
                                            for k, v in result.per_start.items()))
    print(f"overall worst: {result.sup_abs_eps_tail_m * 1e3:.5f} mm ({result.disturbance['family']}, from "
          f"{result.start}); best constant {result.constant_sup_abs_eps_tail_m * 1e3:.5f} mm "
          f"(x{result.sup_abs_eps_tail_m / result.constant_sup_abs_eps_tail_m:.2f})")
    print("rounds: " + ", ".join(f"{r['round']} {r['candidates']} cand. {r['time_s']:.2f} s @ rtol {r['rtol']:.0e}"
                                 for r in result.rounds))
    print(f"candidates tried: {result.candidates_tried}; wall time {elapsed:.2f} s (budget {args.budget:g} s"
          f"{', exhausted' if result.budget_exhausted else ''})")
    if certified is not None:
        ratio = result.tightness_ratio(certified)
        verdict = "VIOLATION: simulated beyond the certified bound" if ratio < 1 else (
            "within the goal (<= 1.5)" if ratio <= 1.5 else "above the goal of 1.5")
        print(f"tightness ratio sos_bound / worst = {certified * 1e3:.4f} / {result.sup_abs_eps_tail_m * 1e3:.4f} "
              f"= {ratio:.3f} ({verdict})")
    if args.json:
        print(json.dumps(result.to_json(), indent=1))


if __name__ == "__main__":
    main()
