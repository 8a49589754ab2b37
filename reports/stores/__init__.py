"""The pages of sweep stores, one module per kind of store; :mod:`reports.stores.common` is what they share.

===========================  =====================================  ===============================
module                       store                                  page
===========================  =====================================  ===============================
``paper_grid``               the paper's point sweep (a grid)       ``sweep.html.j2``
``paper_boxes``              the paper's box sweep (``mode =        ``boxes.html.j2``
                             "boxes"``)
``model_file``               a model file's sweep, points or boxes  ``model_sweep.html.j2``
===========================  =====================================  ===============================

Every page extends ``store.html.j2`` (header, soundness banner, reproducibility block with the
stored spec and versions: :func:`reports.stores.common.provenance`). :data:`reports.render.STORE_PAGES`
decides which page a store gets. The paper's two kinds of store and a model file's differ in
their schema (both in :mod:`sweeps.schema`, one per target), so their pages read different
variables; a model file's classes report through one store whatever their family.
"""
