"""The figure of a sampled-data loop's certificate (``[sampling]``, ``[controller]``): its staircase simulation.

A sampled-data loop is a plant under controls computed at the sampling instants and held between them, not
a field whose phase portrait or certified region could be drawn. Its page shows what
``lyapcheck simulate FILE --plot`` draws for it, by the same code
(:func:`lyapcheck.models.surfaces.sampled_simulate.run_sampled` and its
:func:`~lyapcheck.models.surfaces.sampled_simulate.plot_sampled`): from the equilibrium and starts near it
(:func:`~lyapcheck.models.surfaces.sampled_simulate.default_starts`, ``simulate``'s own), each state
against time, each held control as a staircase (one value per period), and for two states the phase
plane; over ``simulate``'s default horizon. The plot is saved as SVG under the reports' pinned settings
(:func:`reports.figures.to_svg`'s: a fixed id salt, text as paths, lines simplified) with its date
removed, so that the same certificate gives the same page.

The simulation is evidence, never a status: the caption says how many of its trajectories converged and
how many diverged, beside the classes' exact answers.
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

from reports.figures import SIMPLIFY_THRESHOLD, Figure, compact_svg

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.sampling import SampledModel

#: matplotlib's SVG metadata (its date, unless SOURCE_DATE_EPOCH is set): removed, for reproducible pages
_METADATA: Final = re.compile(rb"<metadata>.*?</metadata>", re.S)


def staircase_figure(model: "SampledModel") -> Figure:
    """The staircase simulation of a sampled-data loop (module doc) as a page figure.

    Parameters
    ----------
    model
        The loop, read from the certificate's stored text
        (:func:`lyapcheck.models.language.sampling.parse_sampled`).

    Returns
    -------
    Figure
        The SVG, its caption and alt text; ``data`` holds the simulation's counts (``trajectories``,
        ``converged``, ``diverged``), its horizon ``t_end_s`` and ``periods``.
    """
    import matplotlib

    from lyapcheck.models.surfaces.sampled_simulate import default_starts, run_sampled

    starts, how = default_starts(model)
    with tempfile.TemporaryDirectory(prefix="lyapcheck-report-") as tmp:
        path = Path(tmp) / "staircase.svg"
        # the reports' SVG settings (reports.figures.to_svg), read by matplotlib when the plot is saved
        with matplotlib.rc_context({"svg.hashsalt": "lyapcheck-report", "svg.fonttype": "path",
                                    "path.simplify": True, "path.simplify_threshold": SIMPLIFY_THRESHOLD}):
            doc: dict[str, Any] = run_sampled(model, starts, how, plot=str(path)).document
        svg = compact_svg(_METADATA.sub(b"", path.read_bytes()))
    total, converged, diverged = doc["n_trajectories"], doc["n_converged"], doc["n_diverged"]
    period = float(model.period)
    controls = ", ".join(f"{u} = {model.controller_text[u]}" for u in model.controls)
    caption = (f"The loop simulated from {total} starts ({how}) over {doc['t_end_s']:.6g} s ({doc['periods']} "
               f"periods of {period:.6g} s), as lyapcheck simulate --plot draws it: each state against time and "
               f"each control ({controls}) computed at the sampling instants and held over the period (a "
               f"staircase); dashed: diverged. {converged} converged to the equilibrium, {diverged} diverged. "
               "Evidence, not proof: the statuses above come from exact checks.")
    alt = (f"Time histories of the states and the held controls of {model.name}, sampled every {period:.6g} s: "
           f"{converged} of {total} simulated trajectories converged, {diverged} diverged.")
    return Figure(svg, caption, alt, {"trajectories": total, "converged": converged, "diverged": diverged,
                                      "t_end_s": doc["t_end_s"], "periods": doc["periods"]})


__all__ = ["staircase_figure"]
