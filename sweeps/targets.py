"""What a sweep runs on: its targets, each an input kind with its condition classes, in one table.

One pipeline serves every target: one spec reader (:func:`load_any_spec`), one schema
(:mod:`sweeps.schema`), one store (:mod:`sweeps.store`), one evaluate module (:mod:`sweeps.evaluate`),
one run loop (:mod:`sweeps.run`) and one summary module (:mod:`sweeps.summary`). A target says which
of their pieces are its own:

======  ======================================  ===============================================  ==============
target  its specs                               its classes                                      layouts
======  ======================================  ===============================================  ==============
model   ``[sweep] model = "FILE.toml"``         :data:`lyapcheck.models.classes.registry.CLASSES`         points, boxes
        (any polynomial or rational model,      (``candidate`` with ``[sweep] candidate``;
        or a loop with functions)               boxes: those with box certificates; the same
                                                on every loop)
paper   the paper's sections (gains, swimmer,   the paper's condition classes                    points (and its
        ...) with ``[[sweep.axes]]``            (:data:`sweeps.schema.CLASSES`; boxes:           quadtree), boxes
                                                :data:`sweeps.spec.BOX_CLASSES`)
======  ======================================  ===============================================  ==============

The paper's loop is one model among these: its classes are classes of the paper's model, run by the
same loop into the same kinds of store. A class declared in :data:`lyapcheck.models.classes.registry.CLASSES`
reaches sweeps through the model target's class list: its ``status_<class>`` variable, its unit and
its summary are derived from the list, its key figures from its entry (:data:`sweeps.schema.FIGURES`),
so a new family of classes needs no change here. A new input kind is one more row: a
:class:`SweepTarget` in :data:`TARGETS`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Final, Mapping, Protocol

from lyapcheck.errors import InvalidParameter
from sweeps.run import Progress, run_boxes, run_model_sweep, run_sweep
from sweeps.runners import Runner, make_runner
from sweeps.spec import (
    BOX_CLASSES, MODEL_BOX_CLASSES, MODEL_POINT_CLASSES, ModelSweepSpec, SweepSpec, parse_model_spec, parse_spec,
    read_spec_text,
)
from sweeps.schema import CLASSES


class SweepTarget(Protocol):
    """One input kind of a sweep (module docstring)."""

    @property
    def name(self) -> str:
        """The target's name (``model``, ``paper``)."""
        ...

    def claims(self, data: Mapping[str, Any]) -> bool:
        """Whether a spec's TOML (parsed) is for this target."""
        ...

    def parse(self, text: str, source: str) -> Any:
        """The validated spec (one-line errors naming the field)."""
        ...

    def classes(self, mode: str) -> tuple[str, ...]:
        """The classes a sweep of this target can run in ``mode`` (``points`` or ``boxes``)."""
        ...

    def run(self, spec: Any, out: str | Path, *, runner: Runner, progress: Progress | None,
            on_ready: Callable[[], None] | None) -> Any:
        """Run or resume ``spec`` into the store at ``out``; what the run did."""
        ...

    def summary(self, spec: Any, out: str | Path) -> Any:
        """The summary of the store at ``out`` (with ``to_json`` and ``violations``)."""
        ...

    def exportable(self, spec: Any) -> str | None:
        """None when the store can be exported to NetCDF/CSV, else why not (one line)."""
        ...


@dataclass(frozen=True)
class ModelFileTarget:
    """A model file's parameters, swept point by point or box by box."""

    name: str = "model"

    def claims(self, data: Mapping[str, Any]) -> bool:
        sweep = data.get("sweep")
        return isinstance(sweep, Mapping) and "model" in sweep

    def parse(self, text: str, source: str) -> ModelSweepSpec:
        return parse_model_spec(text, source=source)

    def classes(self, mode: str) -> tuple[str, ...]:
        return MODEL_POINT_CLASSES if mode == "points" else MODEL_BOX_CLASSES

    def run(self, spec: Any, out: str | Path, *, runner: Runner, progress: Progress | None,
            on_ready: Callable[[], None] | None) -> Any:
        return run_model_sweep(spec, out, runner=runner, progress=progress, on_ready=on_ready)

    def summary(self, spec: Any, out: str | Path) -> Any:
        from sweeps.summary import open_summary

        return open_summary(out, spec)

    def exportable(self, spec: Any) -> str | None:
        return ("absent for a model sweep (its store holds certificates as text: read it with xarray, or render "
                "it with lyapcheck report)")


@dataclass(frozen=True)
class PaperTarget:
    """The paper's closed loop (ILOS guidance with the ODS): its gains and disturbance bound swept."""

    name: str = "paper"

    def claims(self, data: Mapping[str, Any]) -> bool:
        return True  # the paper's specs came first and name no model: every other spec is one

    def parse(self, text: str, source: str) -> SweepSpec:
        return parse_spec(text, source=source)

    def classes(self, mode: str) -> tuple[str, ...]:
        return CLASSES if mode == "points" else BOX_CLASSES

    def run(self, spec: Any, out: str | Path, *, runner: Runner, progress: Progress | None,
            on_ready: Callable[[], None] | None) -> Any:
        if spec.mode == "boxes":
            return run_boxes(spec, out, runner=runner, progress=progress, on_ready=on_ready)
        return run_sweep(spec, out, runner=runner, progress=progress, on_ready=on_ready)

    def summary(self, spec: Any, out: str | Path) -> Any:
        from sweeps.store import BoxStore, Store
        from sweeps.summary import summarize, summarize_boxes

        if spec.mode == "boxes":
            return summarize_boxes(BoxStore.open_or_create(out, spec))
        return summarize(Store.open_or_create(out, spec))

    def exportable(self, spec: Any) -> str | None:
        if spec.mode == "boxes":
            return ("absent for a box sweep (its store is one table of boxes: read it with xarray, or render it "
                    "with lyapcheck report)")
        return None


#: every target, in the order a spec is offered to them (the paper's, which claims any spec, last)
TARGETS: Final[tuple[SweepTarget, ...]] = (ModelFileTarget(), PaperTarget())


def target_for_text(text: str) -> SweepTarget:
    """The target a spec's TOML is for (the paper's when it is not TOML: its reader says why)."""
    import tomllib

    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        data = {}
    return next(t for t in TARGETS if t.claims(data))


def target_of(spec: Any) -> SweepTarget:
    """The target of a validated spec."""
    name = "model" if isinstance(spec, ModelSweepSpec) else "paper"
    return next(t for t in TARGETS if t.name == name)


def names_a_model(text: str) -> bool:
    """Whether a spec's TOML names a model file (``[sweep] model``); False when it is not TOML."""
    return target_for_text(text).name == "model"


def load_any_spec(path: str | Path) -> SweepSpec | ModelSweepSpec:
    """The one spec reader: a spec file of any target, validated by that target."""
    text = read_spec_text(path)
    spec: SweepSpec | ModelSweepSpec = target_for_text(text).parse(text, str(path))
    return spec


def sweep_any(spec: SweepSpec | ModelSweepSpec, out: str | Path, *, scheduler: str | None = None,
              workers: int | None = None, exports: tuple[str | Path, ...] = (), progress: Progress | None = None,
              on_ready: Callable[[], None] | None = None) -> tuple[Any, Any]:
    """Run or resume ``spec`` (of any target) into ``out``, then write ``exports``; returns
    (the store's summary, what the run did)."""
    from sweeps.export import export

    target = target_of(spec)
    refusal = target.exportable(spec)
    if exports and refusal is not None:
        raise InvalidParameter("export", refusal, str(exports[0]))
    run = target.run(spec, out, runner=make_runner(scheduler=scheduler, workers=workers), progress=progress,
                     on_ready=on_ready)
    summary = target.summary(spec, out)
    for file in exports:
        export(out, file)
    return summary, run


__all__ = ["SweepTarget", "ModelFileTarget", "PaperTarget", "TARGETS", "target_for_text", "target_of", "names_a_model",
           "load_any_spec", "sweep_any"]
