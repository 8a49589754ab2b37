"""What a certificate page says about the model it certifies, one module per kind of model.

The certificate page (:mod:`reports.certificate_page`) is one page for every document: verdict,
the table of classes, each class's section (:mod:`reports.sections`) and the reproducibility
block. A *subject* supplies the rest, for its kind of model: the header and its alarms, the
model's own sections before and after the classes (the paper's gains, error dynamics,
simulation and claims ledger; a model file's tables, field, phase portrait and exact re-check),
and the model's part of the reproducibility block. :mod:`reports.subjects.base` is the
interface; :mod:`reports.subjects.paper` and :mod:`reports.subjects.model_file` the two kinds.
"""
