"""Where lyapcheck's global certificates stop on networks of 2 to 30 states (issue 43).

Four families of :mod:`networks`, each at a list of sizes: the ring of Duffing oscillators and
the platoon with ``sos_gas`` (GAS); LyZNet's coupled pairs (polynomial) and the ring grid of
generators (swing equations, ``sin``) with ``roa``. Per model, in a fresh process each, whole process timed:

* ``lyapcheck certify FILE --classes CLASS --out CERT`` with an empty certificate store
  (``LYAPCHECK_CACHE_DIR``): status, wall time, peak memory (the child's maximum resident set,
  from ``os.wait4``), and the method the certificate names (``lyapunov`` for one Gram matrix,
  ``lyapunov_cliques`` for V as a sum over cliques of the states);
* ``lyapcheck verify CERT`` when something was certified: the exact re-check alone;
* with ``--drake-python``, for the GAS families, ``completeness/drake_lyapunov.py FILE`` under
  that interpreter (a strict SOS search in pydrake with Clarabel, floating point, V dense), up to
  ``--drake-timeout`` seconds, alternating with lyapcheck.

    python benchmarks/bench_networks.py [--family ring,platoon,grid] [--sizes 2,4,6,8,10,12,16,20,30]
                                        [--time-limit 600] [--drake-python PY] [--drake-timeout 900]
                                        [--cone sdd|dd]

``--cone sdd`` (or ``dd``) forces every program of ``sos_gas`` into that cone (SDSOS or DSOS, dense and
cliques alike) through the benchmark knob ``LYAPCHECK_FORCE_CONE`` (not a user option): the cones
measured alone. Without it, ``sos_gas`` uses them only as its fallback, where the semidefinite forms
are too large; the method column then reads ``lyapunov/sdd`` (the certificate's ``cone``).

Prints one row per model and the issue's targets beside the figures (GAS for the ring at
n = 8 ... 16 within 120 s, at 20 and 30 within 600 s, peak memory below 8 GB at 30): a report,
not an assertion (this machine is shared; the tests assert behaviour, never a time).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import networks  # noqa: E402  (the family generators beside this script)

CLASS_OF = {"ring": "sos_gas", "platoon": "sos_gas", "swarm": "sos_gas", "chain": "sos_gas", "pairs": "roa",
            "grid": "roa"}
#: issue 43's targets for the ring (seconds by size), reported beside the figures
RING_TARGET_S = {8: 120, 10: 120, 12: 120, 16: 120, 20: 600, 30: 600}
MEMORY_TARGET_GB = 8.0


def model_text(family: str, n: int) -> str | None:
    """The family's model with ``n`` states, or None where the family has no such size."""
    if family == "swarm" and n < 4:
        return None  # (two oscillators at least)
    if family == "grid":
        return networks.grid((n + 1) // 2) if n % 2 == 1 and n >= 3 else None
    return networks.FAMILIES[family](n // 2) if n % 2 == 0 and n >= 2 else None


def timed(command: list[str], env: dict[str, str], timeout: float | None) -> tuple[int | None, float, float, str]:
    """Exit code (None on timeout), wall seconds, peak resident memory of the child in GB (its own
    rusage, reaped with ``os.wait4``), and its output."""
    start = time.perf_counter()
    with tempfile.TemporaryFile("w+") as out:
        child = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT, env=env)
        code: int | None = None
        while True:
            pid, status, usage = os.wait4(child.pid, os.WNOHANG)
            if pid:
                code = os.waitstatus_to_exitcode(status)
                break
            if timeout is not None and time.perf_counter() - start > timeout:
                child.kill()
                _, _, usage = os.wait4(child.pid, 0)
                break
            time.sleep(0.05)
        child.returncode = code if code is not None else -9  # reaped here: Popen must not wait again
        wall = time.perf_counter() - start
        out.seek(0)
        text = out.read()
    return code, wall, usage.ru_maxrss / 1e6, text


def run_lyapcheck(path: Path, cls: str, limit: float, work: Path, cone: str | None = None) -> dict[str, Any]:
    env = dict(os.environ, LYAPCHECK_CACHE_DIR=str(work / "store"))
    if cone:
        env["LYAPCHECK_FORCE_CONE"] = cone
    cert = work / (path.stem + ".json")
    command = [sys.executable, "-m", "lyapcheck", "certify", str(path), "--classes", cls, "--time-limit", str(limit),
               "--out", str(cert)]
    code, wall, peak, text = timed(command, env, timeout=limit * 2 + 120)
    row: dict[str, Any] = {"seconds": round(wall, 1), "peak_gb": round(peak, 2), "status": "timeout" if code is None
                           else "error", "method": None, "verify_s": None}
    if cert.exists():
        data = json.loads(cert.read_text())
        condition = data["conditions"].get(cls, {})
        row["status"] = condition.get("status", "error")
        found = condition.get("certificate") or {}
        row["method"] = found.get("kind") if "cone" not in found else f"{found.get('kind')}/{found['cone']}"
        if row["status"] == "certified":
            vcode, vwall, _, vtext = timed([sys.executable, "-m", "lyapcheck", "verify", str(cert)], env, timeout=1800)
            row["verify_s"] = round(vwall, 1) if vcode == 0 else "FAILED"
            if vcode != 0:
                row["verify_output"] = vtext.strip()[-400:]
        detail = condition.get("summary", "")
        row["detail"] = detail[:90]
        if row["status"] == "certified" and "level" in condition:
            row["detail"] = (f"level {condition['level']:.4g}, share of the simulated region of attraction "
                             f"{condition.get('roa_share', float('nan')):.1%}, ball radius "
                             f"{condition.get('ball_radius', float('nan')):.3g}")
    else:
        row["detail"] = text.strip().splitlines()[-1][:90] if text.strip() else ""
    return row


def run_drake(python: str, path: Path, timeout: float) -> dict[str, Any]:
    command = [python, str(HERE / "completeness" / "drake_lyapunov.py"), str(path), "--degrees", "2,4"]
    code, wall, peak, text = timed(command, dict(os.environ), timeout=timeout)
    if code is None:
        return {"seconds": round(wall, 1), "found": f"no answer in {timeout:.0f} s", "peak_gb": round(peak, 2)}
    try:
        answer = json.loads(text.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return {"seconds": round(wall, 1), "found": f"error (exit {code})", "peak_gb": round(peak, 2)}
    return {"seconds": round(wall, 1), "found": "found" if answer.get("certified") else answer.get("status"),
            "peak_gb": round(peak, 2)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--family", default="ring,platoon,pairs,grid")
    parser.add_argument("--sizes", default="2,4,6,8,10,12,16,20,30")
    parser.add_argument("--time-limit", type=float, default=600.0)
    parser.add_argument("--drake-python", default=None)
    parser.add_argument("--drake-timeout", type=float, default=900.0)
    parser.add_argument("--cone", choices=("sdd", "dd"), default=None,
                        help="force sos_gas's programs into this cone (the LYAPCHECK_FORCE_CONE knob)")
    args = parser.parse_args(argv)
    sizes = [int(s) for s in args.sizes.split(",")]
    print(f"{'family':8} {'n':>3} {'class':8} {'status':14} {'method':22} {'s':>7} {'GB':>5} {'verify s':>8}  "
          f"{'target':>7}  {'Drake':>20}")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for family in args.family.split(","):
            cls = CLASS_OF[family]
            for size in sizes:
                n = size if family != "grid" else size - (1 - size % 2)
                text = model_text(family, n)
                if text is None:
                    continue
                path = work / f"{family}-{n}.toml"
                path.write_text(text)
                ours = run_lyapcheck(path, cls, args.time_limit, work, args.cone)
                drake = "-"
                if args.drake_python and cls == "sos_gas":
                    d = run_drake(args.drake_python, path, args.drake_timeout)
                    drake = f"{d['found']} {d['seconds']} s"
                target = f"{RING_TARGET_S[n]} s" if family == "ring" and n in RING_TARGET_S else "-"
                print(f"{family:8} {n:>3} {cls:8} {ours['status']:14} {str(ours['method']):22} {ours['seconds']:>7} "
                      f"{ours['peak_gb']:>5} {str(ours['verify_s']):>8}  {target:>7}  {drake:>20}", flush=True)
                if ours["status"] != "certified" or cls == "roa":
                    print(f"{'':12} {ours.get('detail', '')}", flush=True)
                if "verify_output" in ours:
                    print(f"{'':12} verify: {ours['verify_output']}", flush=True)
    print(f"targets: ring GAS within the seconds shown; peak memory below {MEMORY_TARGET_GB} GB at n = 30")
    return 0


if __name__ == "__main__":
    sys.exit(main())
