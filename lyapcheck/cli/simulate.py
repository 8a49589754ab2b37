"""``lyapcheck simulate``: run a preset or a scenario TOML through :func:`lyapcheck.api.simulate`,
or any closed loop of a model file (``--model FILE``) through :mod:`lyapcheck.models.surfaces.simulate`.

Exit codes (DESIGN.md): 0 the simulation ran and the loop did not diverge; 1 it ran but the
loop diverged (the tail of ``|eps|`` went beyond the initial error, or the integrator failed,
e.g. the printed ODS controller; with ``--model``: a trajectory left the escape box or the
integrator failed, or a simulated tail sup exceeded a certified bound); 2 bad input.
"""

from __future__ import annotations

from contextlib import contextmanager
from typing import Any, Iterator

import click

from lyapcheck.cli.common import EXIT_NEGATIVE, EXIT_OK, emit_json, one_line_errors


def _print_table(doc: dict[str, Any]) -> None:
    from rich.console import Console

    from lyapcheck.cli.tables import print_paper_simulation

    print_paper_simulation(Console(), doc, _disturbance_text(doc["disturbance"]))


def _disturbance_text(d: dict[str, Any]) -> str:
    parts = [d["kind"]]
    for key, value in d.items():
        if key in ("kind",):
            continue
        parts.append(f"{key} = {value}")
    return "; ".join(parts)


def _print_worst_case(doc: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.text import Text

    from lyapcheck.cli.tables import say

    console = Console()
    say(console, Text.assemble(("worst disturbance found", "bold"),
                               f" ({doc['scenario']}, |d| <= {doc['d_max_m_s'] * 1e3:.4g} mm/s): tail sup |eps| = "
                               f"{doc['sup_abs_eps_tail_m'] * 1e3:.4g} mm (constant d*: "
                               f"{doc['constant_sup_abs_eps_tail_m'] * 1e3:.4g} mm)"))
    say(console, f"disturbance: {_disturbance_text(doc['disturbance'])}")
    say(console, f"{doc['candidates_tried']} candidates; a search, not a proof: the certified bound is the proof")


def _print_map_lines(doc: dict[str, Any]) -> None:
    """``simulate`` of a discrete-time map: its iterates' counts and each output's tail sup, in lines."""
    from rich.console import Console

    from lyapcheck.cli.tables import figure, say

    console = Console()
    w0, w1 = doc["tail_window_steps"]
    say(console, f"lyapcheck simulate: {doc['model']['name']}, a discrete-time map iterated {doc['steps']} steps "
                 f"(disturbances held at 0)")
    say(console, f"starts: {doc['n_trajectories']} ({doc['starts_from']}); converged: {doc['n_converged']}, "
                 f"diverged: {doc['n_diverged']}")
    for y, value in doc["sup_abs_output_tail"].items():
        say(console, f"tail sup |{y} - {y}_eq| over steps {w0}-{w1}: {figure(value)}")


def _print_sampling_line(doc: dict[str, Any]) -> None:
    """``simulate`` of a sampled-data loop: the period, the held controls and the horizon in periods."""
    from rich.console import Console

    from lyapcheck.cli.tables import figure, say

    laws = ", ".join(f"{u} = {law}" for u, law in doc["sampling"]["controller"].items())
    say(Console(), f"sampled-data loop: the plant integrated between samples every {figure(doc['period_s'])} s, "
                   f"{laws} held (zero-order hold); {doc['periods']} periods")


def _print_model_table(doc: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.text import Text

    from lyapcheck.cli.tables import figure, print_model_simulation, say

    if doc.get("time") == "discrete":
        _print_map_lines(doc)
        return
    console = Console()
    if doc.get("mode") == "sampled":
        _print_sampling_line(doc)
    print_model_simulation(console, doc)
    if doc.get("field"):  # a loop with functions: what was integrated
        say(console, f"field: {doc['field']}")
    angles = doc.get("angles_modulo_2pi") or []
    modulo = f" (modulo 2 pi in {', '.join(angles)})" if angles else ""
    say(console, f"starts: {len(doc['starts'])} ({doc['starts_from']}); converged = final state within "
                 f"1e-3 state scales of the equilibrium{modulo}")
    failed = [t for t in doc["trajectories"] if t["diverged"]]
    if failed:
        first = failed[0]
        start = ", ".join(f"{k}={figure(v)}" for k, v in doc["starts"][first["start"]].items())
        say(console, Text.assemble((f"{len(failed)} trajectories diverged", "bold red"),
                                   f", e.g. from ({start}) under {first['scenario']}: {first['failure'] or ''}"))


def _model_disturbance_text(d: dict[str, Any]) -> str:
    """One line for a model disturbance's JSON description (lyapcheck.models.surfaces.simulate)."""
    def values(v: dict[str, float]) -> str:
        return ", ".join(f"{k} = {x:.6g}" for k, x in v.items())

    if d["kind"] == "constant":
        return f"constant {values(d['d'])}"
    if d["kind"] == "square":
        return (f"square wave {values(d['amplitude'])} (amplitudes), {d['angular_frequency_rad_s']:.4g} rad/s "
                f"({d['frequency_hz']:.4g} Hz), phase {d['phase_rad']:.3g} rad")
    if d["kind"] == "bang-bang":
        return f"bang-bang feedback pushing |{d['output']}| up (direction {d['direction']:+d})"
    return d["kind"]


def _print_model_worst_case(doc: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.text import Text

    from lyapcheck.cli.tables import figure, print_model_worst_case, say

    console = Console()
    tight = doc.get("tightness")
    print_model_worst_case(console, doc, _model_disturbance_text)
    say(console, f"{doc['candidates_tried']} candidates in {doc['wall_time_s']:.1f} s; {doc['note']}")
    if doc["diverged"]:
        say(console, Text(f"{doc['n_diverged']} candidate trajectories diverged under bounded disturbances",
                          style="bold red"))
        for ex in doc["divergence_examples"][:1]:
            say(console, f"e.g. {_model_disturbance_text(ex['disturbance'])}: {ex['failure']}")
    for y, t in (tight or {}).items():
        if t["soundness_violation"]:
            say(console, Text.assemble(("SOUNDNESS VIOLATION", "bold red"),
                                       f": output {y}: the simulated tail sup {figure(t['worst_simulated'])} exceeds "
                                       f"the certified bound {figure(t['certified_bound'])} (tightness_ratio "
                                       f"{figure(t['tightness_ratio'])} < 1)"))
    if doc.get("soundness_violation"):
        click.echo("lyapcheck: SOUNDNESS VIOLATION: a simulated tail sup exceeds a certified bound (tightness_ratio "
                   "< 1); please report it", err=True)


#: the API's argument names -> this command's flags: the API's errors name its arguments (``t_end``,
#: ``settings``), the command's name what the user typed (``--t-end``, ``--set``)
API_FLAGS = {"t_end": "t-end", "scenarios": "scenario", "budget_s": "budget", "worst_case": "worst-case",
             "settings": "set"}
#: phrases of the API's messages that name an argument -> the same in flags
API_PHRASES = {"worst_case=True": "--worst-case", "as x0)": "with --x0)"}


@contextmanager
def _flag_names() -> Iterator[None]:
    """Re-raise the API's errors in the command's words (:data:`API_FLAGS`, :data:`API_PHRASES`)."""
    from lyapcheck.cli.inputs import flag_names
    from lyapcheck.errors import InvalidParameter

    try:
        with flag_names():  # settings['mu'] -> --set mu, as certify says it
            yield
    except InvalidParameter as exc:
        expected = exc.expected
        for phrase, flag in API_PHRASES.items():
            expected = expected.replace(phrase, flag)
        if exc.field not in API_FLAGS and expected == exc.expected:
            raise
        raise InvalidParameter(API_FLAGS.get(exc.field, exc.field), expected, exc.got) from None


def _run_model(model_file: str, settings: tuple[str, ...], x0: tuple[str, ...], grid: int | None,
               t_end: str | None, scenario_kinds: tuple[str, ...], frequencies: str | None, worst_case: bool,
               budget: float, certificate: str | None, plot: str | None, as_json: bool, steps: str | None = None
               ) -> None:
    """``simulate --model``: call the API, print, exit (0, or 1 on divergence or a violation)."""
    from lyapcheck.api import simulate_model_file

    with _flag_names():
        result = simulate_model_file(model_file, settings=settings, x0=x0, grid=grid, t_end=t_end,
                                     scenarios=scenario_kinds or None, frequencies=frequencies,
                                     worst_case=worst_case, budget_s=budget, certificate=certificate, plot=plot,
                                     series=False, steps=steps)
    doc = result.to_json()
    if as_json:
        emit_json(doc)
    elif worst_case:
        _print_model_worst_case(doc)
    else:
        _print_model_table(doc)
    raise SystemExit(EXIT_NEGATIVE if result.diverged else EXIT_OK)


def register(group: click.Group) -> None:
    @group.command()
    @click.argument("files", nargs=-1, type=click.Path(dir_okay=False), metavar="[FILE]")
    @click.option("--preset", type=click.Choice(["paper-ilos", "paper-los-600", "paper-los-1200"]),
                  help="One of the paper's Section 5 simulations.")
    @click.option("--json", "as_json", is_flag=True, help="Print the measured quantities as JSON (SI units).")
    @click.option("--plot", type=click.Path(dir_okay=False), help="Write the Section 5 figures to this PNG.")
    @click.option("--worst-case", is_flag=True, help="Search the worst disturbance |d| <= d* (tail sup |eps|).")
    @click.option("--budget", type=float, default=20.0, show_default=True,
                  help="Wall-time target of --worst-case, seconds.")
    @click.option("--model", "model_file", type=click.Path(dir_okay=False),
                  help="The model file (the same as giving it as FILE, recognised by its [model] or [dynamics] table; "
                       "format: docs/model-files.md).")
    @click.option("--set", "settings", multiple=True, metavar="NAME=VALUE",
                  help="With --model: override a parameter or disturbance bound, e.g. --set mu=2 (repeatable).")
    @click.option("--x0", multiple=True, metavar='"x1=1,x2=0"',
                  help="With --model: an initial state (numbers or unit strings, SI inside; missing states take "
                       "the equilibrium's value). Repeatable.")
    @click.option("--grid", type=int, metavar="N",
                  help="With --model: also start from an N-per-state grid over the model's [domain].")
    @click.option("--t-end", metavar="SECONDS",
                  help="With --model: the horizon (default 40 slowest time constants of the linearisation); "
                       "the tail window is its last 20 %.")
    @click.option("--scenario", "scenario_kinds", multiple=True,
                  type=click.Choice(["none", "constant", "bang-bang", "square"]),
                  help="With --model: disturbance scenarios to run (repeatable; default all that apply).")
    @click.option("--frequencies", metavar='"LO..HI"',
                  help="With --model: the square waves' angular frequencies, rad/s (or with a unit: "
                       '"0.1 Hz..2 Hz"), 8 log-spaced.')
    @click.option("--certificate", type=click.Path(dir_okay=False),
                  help="With --model --worst-case: a certificate with sos_bound certified; prints tightness_ratio "
                       "= certified bound / worst simulated per output (exit 1 if one is below 1).")
    @click.option("--steps", metavar="N", help='With a discrete-time map ([model] time = "discrete"): the number '
                  "of iterations (default 50).")
    @one_line_errors
    def simulate(files: tuple[str, ...], preset: str | None, as_json: bool, plot: str | None, worst_case: bool,
                 budget: float, model_file: str | None, settings: tuple[str, ...], x0: tuple[str, ...],
                 grid: int | None, t_end: str | None, scenario_kinds: tuple[str, ...], frequencies: str | None,
                 certificate: str | None, steps: str | None) -> None:
        """Simulate any closed loop from a model file (FILE or --model FILE), or the paper's
        saturated ILOS/ODS loop (a scenario FILE or a --preset)."""
        from lyapcheck.api import simulate as run_simulation
        from lyapcheck.cli.inputs import check_model_flags, split_model_argument
        from lyapcheck.errors import InvalidParameter

        model_given = {"--set": settings, "--x0": x0, "--grid": grid, "--t-end": t_end,
                       "--scenario": scenario_kinds, "--frequencies": frequencies, "--certificate": certificate,
                       "--steps": steps}
        model_file, scenario = split_model_argument(files[0] if files else None, model_file)
        # a word beside the model file, or after the first file: a value split from --set or --x0, or a second file
        stray = scenario if model_file is not None and scenario is not None else files[1] if len(files) > 1 else None
        if model_file is not None:
            if stray is not None and "=" in stray and x0 and not settings:
                # --x0 x1=1 x2=0: the shell split one start in two words
                raise InvalidParameter("x0", f'one start in one word: use --x0 "{x0[-1]} {stray}"',
                                       f"--x0 {x0[-1]} {stray}")
            check_model_flags(model_file, stray, settings, {"--preset": preset is not None})
            _run_model(model_file, settings, x0, grid, t_end, scenario_kinds, frequencies, worst_case, budget,
                       certificate, plot, as_json, steps)
        if stray is not None:
            raise InvalidParameter("FILE", "one scenario file or model file", " ".join(files))
        used = [flag for flag, value in model_given.items() if value not in (None, ())]
        if used:
            value = model_given[used[0]]
            raise InvalidParameter(used[0].lstrip("-"), "used with a model file (FILE or --model FILE)",
                                   value[0] if isinstance(value, tuple) else value)

        with _flag_names():
            result = run_simulation(scenario, preset=preset, plot=plot, worst_case=worst_case, budget_s=budget,
                                    series=False)
        if as_json:
            emit_json(result.to_json())
        elif worst_case:
            _print_worst_case(result.to_json())
        else:
            _print_table(result.to_json())
        raise SystemExit(EXIT_NEGATIVE if result.diverged else EXIT_OK)
