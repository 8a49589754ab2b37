"""Parameter-space sweeps: where each certificate class holds, cross-checked by simulation.

One pipeline for every target (:mod:`sweeps.targets`: a model file, with the classes of
``lyapcheck.models``; the paper's model, with its own condition classes). Modules, one concern each:

====================  =========================================================================
``targets``           what a sweep runs on: the targets' table, the one spec reader, ``sweep_any``
``spec``              specs of every target: axes, ``[sweep.boxes]``, the paper's and a model file's
``schema``            the store's variables, dtypes, fill values and status codes, per target
``evaluate``          one unit of work: certify points or boxes, cross-check them by simulation
``crosscheck``        the simulation cross-check of a model file's certified point or box
``fast_sector``       the paper's ``sector_ges`` with compiled conic data and Clarabel called directly
``soundness``         the soundness-violation flag and its tolerances
``refine``            the paper's quadtree refinement on a 2-D slice
``store``             the Zarr stores (a grid, a table of boxes): atomic creation, writes, resume
``runners``           in-process, local worker processes, or a Dask cluster
``run``               the one loop: grid of points, quadtree, refinement tree of boxes
``summary``           figures read back from a store of any target
``export``            NetCDF and CSV
====================  =========================================================================

Entry points: :func:`sweeps.targets.sweep_any`, :func:`sweeps.run.run_sweep` and ``lyapcheck sweep``
(:mod:`lyapcheck.cli.sweep`).
"""
