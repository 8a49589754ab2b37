"""Parameter-space sweeps: where each certificate class holds, cross-checked by simulation.

Modules, one concern each:

====================  =========================================================================
``spec``              the sweep spec (TOML), validated through ``lyapcheck.paper.params``
``schema``            the store's variables, dtypes, fill values and status codes
``evaluate``          one unit of work: certify and simulate a batch of points
``fast_sector``       ``sector_ges`` with compiled conic data and Clarabel called directly
``soundness``         the soundness-violation flag and its tolerance
``refine``            quadtree refinement on a 2-D slice
``store``             the Zarr store: atomic creation, chunk writes, resume checks
``runners``           in-process, local worker processes, or a Dask cluster
``run``               the loop that feeds runners and streams results into the store
``summary``           figures read back from a store
``export``            NetCDF and CSV
``model_spec``        a spec that names a model file: its parameters swept as points or boxes
``model_schema``      a model sweep store's variables and attributes
``model_store``       its Zarr store (on ``store``'s helpers)
``model_evaluate``    one unit of a model sweep: certify points or boxes, store certificates
``model_crosscheck``  the simulation cross-check of a certified point or box
``model_run``         the grid or the refinement tree of a model sweep
``model_summary``     shares of the window proved, per status and class
====================  =========================================================================

Entry points: :func:`sweeps.run.run_sweep` and ``lyapcheck sweep`` (:mod:`lyapcheck.cli.sweep`).
"""
