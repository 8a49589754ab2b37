"""The registry of report sections: which module shows which condition class of which model.

======================================  ==============  ==========================================
section (module)                        model           classes
======================================  ==============  ==========================================
``stability.StabilitySection``          a model file    linearization, quadratic, sos_gas, roa,
                                                        candidate
``output_bound.OutputBoundSection``     a model file    sos_bound (one storage function per output)
``safety.SafetySection``                a model file    barrier, reach_avoid (+ their invariant sets)
``model_file.ModelFileSection``         a model file    any other class (fallback)
``model_file.ModelFileSection`` made    a loop with     linearization, quadratic, sos_gas, roa,
for ``RECAST_LOOP``                     functions       candidate, and any other (fallback): recast
                                                        and interval certificates, their sets
``paper.PaperSection``                  the paper's     prop41_ges, prop41_iss, stabcond2,
                                        loop            sector_ges, ultimate_bound, sos_bound, and
                                                        any other (box classes, unknown ones)
======================================  ==============  ==========================================

The certificate page (:mod:`reports.certificate_page`) asks :func:`section_for` for each
condition of a document and shows the :class:`~reports.sections.base.ClassView` it returns;
the phase portrait of a model file (:mod:`reports.phase_portrait`) asks the same section for the
certified sets to draw. A new family of classes is one module with a subclass of
:class:`~reports.sections.base.Section` and one line in :data:`SECTIONS`::

    # reports/sections/barrier.py
    class BarrierSection(ModelFileSection):
        titles = {"barrier": "Barrier certificate: the unsafe set is never reached"}
        def portrait(self, name, cond, n, time_scale):
            B = ExactPolynomial.from_json(cond["certificate"]["B"], n)
            return PortraitPart(sets=(LevelSet(name, "{B <= 0}", B, Fraction(0), "invariant", "#6e40c9",
                                               symbol="B"),))

    # here: SECTIONS = (..., BarrierSection())
"""

from __future__ import annotations

from typing import Final

from reports.sections.base import MODEL_FILE, PAPER, RECAST_LOOP, Section
from reports.sections.model_file import RECAST_TITLES, ModelFileSection
from reports.sections.output_bound import OutputBoundSection
from reports.sections.paper import PaperSection
from reports.sections.safety import SafetySection
from reports.sections.stability import StabilitySection

#: every section, in no particular order (a class name is claimed by one section per model)
#: a loop with functions: one section, the model file's made for its model, shows every class
RECAST_SECTION: Final = ModelFileSection(RECAST_LOOP, RECAST_TITLES)
SECTIONS: Final[tuple[Section, ...]] = (StabilitySection(), OutputBoundSection(), SafetySection(), PaperSection(),
                                        RECAST_SECTION)
#: the section of a class no section names, per model
FALLBACK: Final[dict[str, Section]] = {MODEL_FILE: ModelFileSection(), PAPER: PaperSection(),
                                       RECAST_LOOP: RECAST_SECTION}


def _table() -> dict[tuple[str, str], Section]:
    table: dict[tuple[str, str], Section] = {}
    for section in SECTIONS:
        for name in section.titles:
            if (section.model, name) in table:
                raise RuntimeError(f"two report sections claim the class {name!r} of the model {section.model!r}")
            table[(section.model, name)] = section
    return table


#: (model, class name) -> its section
BY_CLASS: Final = _table()


def section_for(model: str, name: str) -> Section:
    """The section that shows the class ``name`` of a document of ``model`` (:data:`PAPER`, :data:`MODEL_FILE`
    or :data:`~reports.sections.base.RECAST_LOOP`)."""
    found = BY_CLASS.get((model, name))
    if found is not None:
        return found
    if model not in FALLBACK:
        raise ValueError(f"the model of a report section must be one of {sorted(FALLBACK)}; got {model!r}")
    return FALLBACK[model]


__all__ = ["SECTIONS", "FALLBACK", "BY_CLASS", "section_for", "PAPER", "MODEL_FILE", "RECAST_LOOP", "RECAST_SECTION"]
