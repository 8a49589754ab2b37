"""Shared sympy symbols, so every derivation speaks of the same objects.

All physical symbols are real and, where the paper says so, positive. Names follow the
paper's notation.
"""

from __future__ import annotations

import sympy as sp

# guidance gains (eq:los, eq:losdynvar)
alpha_d, sigma0, k_d, Delta = sp.symbols("alpha_d sigma_0 k_d Delta_LOS", positive=True)
#: implicit speed of eq:losdynvar (the paper's equation is read with U = 1 m/s in SI)
U = sp.Symbol("U", positive=True)

# swimmer (eq:e11, Table table:micro)
e11, e11_hat = sp.symbols("e_11 \\hat{e}_11", positive=True)
n_h, r_h = sp.symbols("n_h r_h", positive=True)
theta_h = sp.Symbol("theta_h", positive=True)
xi_par, xi_perp = sp.symbols("xi_par xi_perp", positive=True)
xi_vm, k_h = sp.symbols("xi_vm k_h", positive=True)

# path and state
theta_r = sp.Symbol("theta_r", real=True)
theta = sp.Symbol("theta", real=True)
p_norm = sp.Symbol("|p|", positive=True)
p_x, p_z = sp.symbols("p_x p_z", real=True)
eps, s, z = sp.symbols("varepsilon s z", real=True)

# disturbances and their estimates (eq:notation)
d_x, d_z = sp.symbols("d_x d_z", real=True)
dh_x, dh_z = sp.symbols("\\hat{d}_x \\hat{d}_z", real=True)
d_perp, d_par = sp.symbols("d_mu^perp d_mu^par", real=True)

# ODS (eq:ODS, eq:solFinal)
Omega_SO, Omega_0 = sp.symbols("Omega_SO Omega_0", positive=True)
q1, q2 = sp.symbols("q_1 q_2", positive=True)
lam = sp.Symbol("lambda", nonnegative=True)

# Lyapunov matrix entries (eq:stabCond)
p11, p12, p22 = sp.symbols("p_11 p_12 p_22", real=True)
