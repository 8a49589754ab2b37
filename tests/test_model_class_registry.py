"""The classes of a model file are declared once (lyapcheck.models.classes.registry, issue 29 item 6): what
certify, sweeps and the results' default properties say of them is read from there, and each class
has its report section in the module its family names."""

from __future__ import annotations

from lyapcheck.models.surfaces import certify
from lyapcheck.models.classes import registry as classes
from lyapcheck.results import PROPERTY
from reports.sections import FALLBACK, MODEL_FILE, section_for
from sweeps import evaluate, schema, spec


def test_certify_runs_the_declared_classes_in_their_order() -> None:
    assert certify.MODEL_CLASSES == tuple(c.name for c in classes.CLASSES)
    assert certify.CLEARED_CLASSES == tuple(c.name for c in classes.CLASSES if c.cleared)
    assert set(classes.POINT_ONLY) | set(classes.OVER_BOX) == set(classes.NAMES)
    assert not set(classes.POINT_ONLY) & set(classes.OVER_BOX)


def test_sweeps_read_the_declarations() -> None:
    assert spec.MODEL_USER_CLASSES == tuple(c.name for c in classes.CLASSES if c.user_given)
    assert spec.MODEL_POINT_ONLY_CLASSES == tuple(c.name for c in classes.CLASSES if not c.over_box)
    assert spec.MODEL_BOX_CLASSES == tuple(c.name for c in classes.CLASSES if c.over_box)
    assert evaluate.MODEL_STABILITY_CLASSES == tuple(c.name for c in classes.CLASSES if c.stability)
    for c in classes.CLASSES:
        assert schema.FIGURES.get(c.name, ()) == c.figures
        assert schema.OUTPUT_FIGURES.get(c.name) == c.output_figure


def test_the_default_property_of_each_class_is_the_declared_one() -> None:
    """lyapcheck.results.PROPERTY (below lyapcheck.models, so it cannot read the list) says the same."""
    for c in classes.CLASSES:
        assert PROPERTY.get(c.name) == c.proves, c.name


def test_each_class_has_its_section_in_its_familys_module() -> None:
    for c in classes.CLASSES:
        section = section_for(MODEL_FILE, c.name)
        assert section is not FALLBACK[MODEL_FILE], c.name
        assert type(section).__module__ == f"reports.sections.{c.family}", c.name
