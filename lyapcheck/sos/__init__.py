"""The SOS engine: everything a sum-of-squares certificate needs, for the paper's classes and for
the generic classes of a model file alike.

- :mod:`lyapcheck.sos.sdp`: the bridge to the conic solver (cvxpy + Clarabel), with one status map;
"""
