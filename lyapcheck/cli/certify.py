"""``lyapcheck certify`` and ``lyapcheck verify`` (contract in DESIGN.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import click

from lyapcheck.cli.common import EXIT_NEGATIVE, EXIT_OK, emit_json, one_line_errors
from lyapcheck.errors import InvalidParameter

#: command-line flag -> parameter key (lyapcheck.paper.params.FIELDS)
FLAG_KEYS = {
    "alpha_d": "gains.alpha_d", "sigma0": "gains.sigma0", "kd": "gains.k_d", "delta_los": "gains.delta_los",
    "e11": "swimmer.e11", "omega_so": "actuation.omega_so", "d_max": "disturbance.d_max",
}

def _print_table(doc: dict[str, Any], verbose: bool = False, unmet: Sequence[str] = ()) -> None:
    """The conditions as a table that fits the terminal (no cell cut inside a word or a number:
    :mod:`lyapcheck.cli.tables`), then the answer to each question, the verdict and what it means."""
    from rich.console import Console

    from lyapcheck.cli.tables import print_answers, print_conditions

    console = Console()
    print_conditions(console, doc, verbose=verbose)
    print_answers(console, doc, unmet)


def exit_code(doc: dict[str, Any], unmet: Sequence[str] = ()) -> int:
    """0 when no asked question is answered negatively, some claim passed its exact check and every
    ``--require`` is met; else 1 (README, "Exit codes")."""
    from lyapcheck.answers import OK_VERDICTS

    return EXIT_OK if doc.get("verdict") in OK_VERDICTS and not unmet else EXIT_NEGATIVE


def _finish(result: Any, out: str | None, report: str | None, as_json: bool, write_report: Any,
            required: Sequence[str] = (), verbose: bool = False) -> None:
    """Write what was asked, print the table or the JSON, exit 0 or 1 (:func:`exit_code`)."""
    from lyapcheck.answers import unmet_requirements

    if out:
        result.write(out)
    if report:
        as_pdf = Path(report).suffix.lower() == ".pdf"
        write_report(result, html=None if as_pdf else report, pdf=report if as_pdf else None)
    doc = result.to_json()
    unmet = unmet_requirements(doc.get("conditions") or {}, required)
    if as_json:
        emit_json(doc)
    else:
        _print_table(doc, verbose, unmet)
    # a simulated trajectory that contradicts a certified claim (roa's set, a barrier's unsafe set):
    # the proof or the simulation is wrong, and a script must not read the run as a success
    violated = [name for name, c in (doc.get("conditions") or {}).items()
                if isinstance(c, dict) and c.get("soundness_violation")]
    if violated:
        click.echo(f"SOUNDNESS VIOLATION: a simulated trajectory contradicts the certified {', '.join(violated)} "
                   "(please report it)", err=True)
        raise SystemExit(EXIT_NEGATIVE)
    raise SystemExit(exit_code(doc, unmet))


def _extremum(model_file: str, maximize: str | None, minimize: str | None, steps: str | None,
              boxes: Sequence[str], report: str | None, out: str | None, as_json: bool, **certify_args: Any) -> None:
    """``--maximize`` / ``--minimize``: the search (:func:`lyapcheck.api.certify_extremum`), a line per value
    tried and the answer; ``--out`` the proved value's certificate. Exit 0 when a value was proved."""
    from lyapcheck.api import certify_extremum

    if maximize is not None and minimize is not None:
        raise InvalidParameter("minimize", "not given with --maximize (one search at a time)", minimize)
    if maximize is None and minimize is None:
        raise InvalidParameter("steps", "used with --maximize or --minimize", steps)
    if boxes:
        raise InvalidParameter("box", "not given with --maximize/--minimize (the search varies one parameter)",
                           " ".join(boxes))
    found = certify_extremum(model_file, str(maximize if maximize is not None else minimize),
                             direction="max" if maximize is not None else "min",
                             steps=steps, **certify_args)
    written = found.document()  # the proved value's certificate with the search's table (its report shows both)
    if out and written is not None:
        import json

        from lyapcheck.fileio import atomic_write

        atomic_write(out, json.dumps(written, indent=2) + "\n")
    if report is not None and written is not None:  # the page of lyapcheck report on that document
        from reports.render import certificate_report

        certificate_report(written, report)
    if as_json:
        emit_json({"extremum": found.to_json(),
                   "certificate": None if found.proved_result is None else found.proved_result.to_json()})
    else:
        for step in found.steps:
            click.echo(f"  {found.parameter} = {step.value_text():>14}  {step.outcome:10}  verdict {step.verdict}"
                       f"  ({step.seconds:.1f} s)")
        click.echo(found.sentence())
        if out and found.proved_result is not None:
            click.echo(f"certificate of {found.parameter} = {found.proved_text()} written to {out}")
        if report is not None:
            click.echo(f"report of the search written to {report}" if written is not None else
                       "no report: no value was proved (the values tried are listed above)")
    raise SystemExit(EXIT_OK if found.proved is not None else EXIT_NEGATIVE)


#: the longest ``--time-limit`` accepted, in seconds (a day: a class that needs more is not one to wait for)
MAX_TIME_LIMIT_S = 86_400.0


def _time_limit(text: str | None) -> float | None:
    """``--time-limit SECONDS`` (None: the default); a one-line error naming ``time-limit``."""
    if text is None:
        return None
    try:
        seconds = float(text)
    except ValueError:
        seconds = float("nan")
    if not 0 < seconds <= MAX_TIME_LIMIT_S:  # (nan fails too)
        raise InvalidParameter("time-limit", f"a number of seconds in (0, {MAX_TIME_LIMIT_S:g}]", text)
    return seconds


def register(group: click.Group) -> None:
    @group.command()
    @click.argument("files", nargs=-1, type=click.Path(dir_okay=False), metavar="[FILE]")
    @click.option("--model", "model_file", type=click.Path(dir_okay=False),
                  help="The model file (the same as giving it as FILE, which is recognised by its [model] or "
                       "[dynamics] table). Format: docs/model-files.md.")
    @click.option("--set", "settings", multiple=True, metavar="NAME=VALUE",
                  help="A model's parameter or disturbance bound, e.g. --set mu=2 (repeatable).")
    @click.option("--candidate", help='Your own Lyapunov function for a model, e.g. "x1**2 + x2**2".')
    @click.option("--classes", help="Comma-separated condition classes to run (default: all that apply; for the "
                  "paper, 'quick' = the quadratic and arithmetic classes, about 20x faster).")
    @click.option("--box", "boxes", multiple=True, help='Certify a whole box of a model\'s parameters (a loop with '
                  'functions too), e.g. --box "mu=0.8..1.2" (repeatable), or of the paper\'s gains, e.g. --box '
                  '"alpha_d=540..660" --box "k_d=0.1..0.2" (classes prop41_ges, prop41_iss, sector_ges and ges by '
                  'default; --classes all adds ultimate_bound, sos_gas, saturated_loop and sos_bound).')
    @click.option("--json", "as_json", is_flag=True, help="Print the certificate document as JSON.")
    @click.option("--out", type=click.Path(dir_okay=False), help="Write the certificate JSON here.")
    @click.option("--report", type=click.Path(dir_okay=False), help="Write an HTML or PDF report (by extension).")
    @click.option("--alpha-d", help="The paper's loop: ILOS gain alpha_d (1/s).")
    @click.option("--sigma0", help="The paper's loop: integral gain sigma0.")
    @click.option("--kd", help="The paper's loop: damping gain k_d (1/s).")
    @click.option("--delta-los", help='The paper\'s loop: look-ahead distance, e.g. "0.75 mm".')
    @click.option("--e11", help='The paper\'s loop: propulsion constant, e.g. "9.3e-5 m".')
    @click.option("--omega-so", help='The paper\'s loop: step-out frequency, e.g. "2.8 Hz".')
    @click.option("--d-max", help='The paper\'s loop: disturbance bound, e.g. "0.088 mm/s".')
    @click.option("--dynamics", type=click.Choice(["derived", "printed"]), default="derived", show_default=True,
                  help="The paper's loop: error dynamics as derived by lyapcheck or as printed in the paper.")
    @click.option("--linear-views", is_flag=True, help="The paper's loop: add python-control views: poles, P from "
                  "Gamma = I (slower).")
    @click.option("--worst-case", is_flag=True, help="The paper's loop: also search the worst disturbance in "
                  "simulation and report tightness_ratio = certified / simulated beside each certified bound "
                  "(10-20 s).")
    @click.option("--no-store", "no_store", is_flag=True, help="A model file: search every class again, neither "
                  "reading nor writing the certificates kept from earlier runs (a stored certificate is re-checked "
                  "exactly before it is used; LYAPCHECK_CERTIFICATE_STORE=off does the same for every run).")
    @click.option("--require", "require", metavar="PROPS",
                  help="Exit 1 unless each of these is proved, e.g. --require GAS,safety (names: GES, GAS, ROA, "
                       "LES, ISS, ultimate_bound or bounds, safety, reach_avoid; GES meets GAS, GAS meets ROA).")
    @click.option("--degree", "degree", metavar="N", help="A model file: the largest polynomial degree each class "
                  "searches (default: each class's own ladder, e.g. sos_gas 2, 4, 6, 8; higher can prove more and "
                  "costs more).")
    @click.option("--time-limit", "time_limit", metavar="SECONDS", help="A model file: each class's time limit in "
                  "seconds (default 60); past it the class is inconclusive and says so.")
    @click.option("--maximize", "maximize", metavar="NAME=LO..HI", help="A model file: the largest value of one "
                  "parameter (or disturbance bound) in LO..HI at which certify succeeds, by bisection with an exact "
                  "certification at each value; --out writes the certificate of the value proved.")
    @click.option("--minimize", "minimize", metavar="NAME=LO..HI", help="A model file: the smallest such value "
                  "(e.g. the smallest safe gap).")
    @click.option("--steps", "steps", metavar="N", help="With --maximize/--minimize: bisection steps after the "
                  "two ends (default 6).")
    @click.option("--verbose", is_flag=True, help="Show each condition's technical detail (solver statuses, size "
                  "limits) under its summary.")
    @one_line_errors
    def certify(files: tuple[str, ...], dynamics: str, as_json: bool, out: str | None, report: str | None,
                linear_views: bool, classes: str | None, worst_case: bool, boxes: tuple[str, ...],
                model_file: str | None, settings: tuple[str, ...], candidate: str | None, no_store: bool,
                require: str | None, degree: str | None, time_limit: str | None, verbose: bool,
                maximize: str | None, minimize: str | None, steps: str | None, **flags: str | None) -> None:
        """Certify any closed loop from a model file (FILE or --model FILE), or a gain set of the
        paper's ILOS/ODS loop (its worked example: a gain file, flags, or both): every condition
        class, each checked exactly.

        The headline answers each question the model asks: stability (global, region, local,
        unstable, undecided), safety (safe, unsafe with a counterexample, undecided), reach-avoid
        and bounds. Exit 1 when one is answered negatively (unsafe, unstable), when nothing is
        proved, or when --require names a property not proved; else 0.

        Disturbances of a model file: every claim says which disturbances it covers, "all" (for
        every disturbance signal within its bounds: sos_bound, and a stability class whose V
        decreases for every disturbance value, tried where the disturbances vanish at the
        equilibrium) or "zero" (proved with every disturbance held at 0, printed "(d = 0)"). The
        verdict is certified (exit 0) only through a claim that covers the disturbances;
        certified_nominal (exit 0) when only "(d = 0)" claims passed; else not_certified (exit 1).

        Time: each class of a model file stops searching at --time-limit (60 s) and is then
        inconclusive, the others still run; work that overruns it is stopped at 1.5 x 60 + 5 = 95 s.
        One certify --model therefore takes at most about 11 minutes (six classes and the
        denominators' proof, 95 s each, before any --report), and seconds on the shipped examples."""
        from lyapcheck.api import certify as certify_gains
        from lyapcheck.api import report as write_report
        from lyapcheck.sos import sdp

        sdp.LEAN_LAPACK_IMPORT = True  # this process is the command's own (see sdp._load_lapack_modules)
        if no_store:  # the process is the command's own: the switch holds for this run alone
            import os

            from lyapcheck.models.engines.store import STORE_ENV

            os.environ[STORE_ENV] = "off"

        if report is not None and Path(report).suffix.lower() not in (".html", ".pdf"):
            raise InvalidParameter("report", "a file name ending in .html or .pdf", report)
        from lyapcheck.answers import parse_requirements
        from lyapcheck.degrees import check_degree

        required = parse_requirements(require)
        max_degree = check_degree(degree)
        seconds = _time_limit(time_limit)
        overrides = {FLAG_KEYS[k]: v for k, v in flags.items() if v is not None}
        from lyapcheck.cli.inputs import check_model_flags, flag_names, split_model_argument

        model_file, gains = split_model_argument(files[0] if files else None, model_file)
        # a word beside the model file, or after the first file: a value that lost its --set, or a second file
        stray = gains if model_file is not None and gains is not None else files[1] if len(files) > 1 else None
        if model_file is not None:
            paper_flags = {"--linear-views": linear_views, "--worst-case": worst_case, "--dynamics": dynamics != "derived",
                           **{f"--{k.replace('_', '-')}": v is not None for k, v in flags.items()}}
            check_model_flags(model_file, stray, settings, paper_flags)
            if maximize is not None or minimize is not None or steps is not None:
                with flag_names():
                    _extremum(model_file, maximize, minimize, steps, boxes, report, out, as_json, settings=settings,
                              candidate=candidate, classes=classes, require=require, degree=max_degree,
                              time_limit_s=seconds)
            with flag_names():
                result = certify_gains(model=model_file, settings=settings, candidate=candidate, classes=classes,
                                       box=list(boxes) or None, degree=max_degree, time_limit_s=seconds)
            _finish(result, out, report, as_json, write_report, required, verbose)
        if stray is not None:
            raise InvalidParameter("FILE", "one gain file or model file", " ".join(files))
        if settings or candidate is not None:
            raise InvalidParameter("set" if settings else "candidate", "used with a model file",
                                   settings[0] if settings else candidate)
        if maximize is not None or minimize is not None or steps is not None:
            raise InvalidParameter("maximize" if maximize is not None else "minimize" if minimize is not None
                                   else "steps", "used with a model file", maximize or minimize or steps)
        if degree is not None or time_limit is not None:  # the paper's classes have their own degrees and costs
            raise InvalidParameter("degree" if degree is not None else "time-limit", "used with a model file",
                                   degree if degree is not None else time_limit)
        if boxes:
            from lyapcheck.api import certify_box

            if worst_case or linear_views or report:
                raise InvalidParameter("box", "used without --worst-case, --linear-views or --report (a box has "
                                       "no single gain set to simulate)", " ".join(boxes))
            result = certify_box(gains, boxes, dynamics=dynamics, overrides=overrides, classes=classes)
            if out:
                result.write(out)
            doc = result.to_json()
            from lyapcheck.answers import unmet_requirements

            unmet = unmet_requirements(doc.get("conditions") or {}, required)
            if as_json:
                emit_json(doc)
            else:
                _print_table(doc, verbose, unmet)
            raise SystemExit(exit_code(doc, unmet))
        result = certify_gains(gains, dynamics=dynamics, classes=classes, linear_views=linear_views,
                               overrides=overrides, worst_case=worst_case)
        _finish(result, out, report, as_json, write_report, required, verbose)

    @group.command()
    @click.argument("certificate", type=click.Path(dir_okay=False))
    @click.option("--json", "as_json", is_flag=True, help="Print the check results as JSON.")
    @one_line_errors
    def verify(certificate: str, as_json: bool) -> None:
        """Re-check a certificate file exactly (no solver involved)."""
        from lyapcheck.api import verify as verify_certificate

        result = verify_certificate(certificate)
        if as_json:
            emit_json(result.to_json())
        else:
            for check in result.checks:
                click.echo(f"{'ok  ' if check.ok else 'FAIL'} {check.check}: {check.message}")
            click.echo("certificate verified" if result.valid else "certificate FAILS its exact re-check")
        raise SystemExit(EXIT_OK if result.valid else EXIT_NEGATIVE)
