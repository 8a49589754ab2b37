"""Model files of three network families at any size, for the scale benchmark (issue 43).

Each function returns the text of a model file (TOML, the contract of ``docs/model-files.md``):

* :func:`ring` -- ``m`` damped oscillators with hardening (cubic) springs, each coupled to its two
  neighbours on a ring by linear springs; ``n = 2 m`` states. The energy
  ``sum p_k^2/2 + q_k^2/2 + q_k^4/4 + kc/2 sum (q_k - q_(k+1))^2`` decreases along every trajectory
  (its derivative is ``-c sum p_k^2``), and a strict quartic Lyapunov function exists: the origin is
  globally asymptotically stable. The issue's measurement of ``sos_gas`` and Drake was on this family.
* :func:`platoon` -- a chain of ``m`` vehicles (position error, velocity error) following a leader,
  each with a PD spacing law on its predecessor and quadratic drag ``v |v|`` replaced by the cubic
  ``v^3`` (a polynomial loop); ``n = 2 m`` states, GAS (a cascade of stable second-order blocks).
* :func:`coupled_pairs` -- LyZNet's 10-state example grown to ``m`` pairs on a ring (polynomial,
  locally stable only): ``roa`` on a polynomial network;
* :func:`grid` -- ``m`` generators on a ring of lossless lines (the classical swing equations,
  ``delta_k'' = -d delta_k' - b sum sin(delta_k - delta_j)`` relative to the equilibrium, which
  is at 0 by a choice of the injections), with functions (``sin`` of an angle difference): only a
  region of attraction can hold (the loop is periodic in the common angle, the equilibria repeat),
  so this family is for ``roa``. One generator is the reference (its angle is not a state), so
  ``n = 2 m - 1`` states.

None of them is a lyapcheck fixture: they are inputs of :mod:`bench_networks`, generated so that the
size is the only thing that changes within a family.
"""

from __future__ import annotations


def _states(names: list[str]) -> str:
    return "[" + ", ".join(f'"{s}"' for s in names) + "]"


def ring(m: int, damping: str = "1", coupling: str = "0.5") -> str:
    """``m`` damped Duffing oscillators on a ring with linear coupling springs (``m >= 1``)."""
    if m < 1:
        raise ValueError(f"ring: m must be at least 1, got {m}")
    names = [v for k in range(1, m + 1) for v in (f"q{k}", f"p{k}")]
    lines = [f'# A ring of {m} damped oscillators with cubic springs, linear couplings ({2 * m} states).',
             "[model]", f'name = "ring of {m} Duffing oscillators"', f"states = {_states(names)}", "",
             "[parameters]", f'c = "{damping}"', f'kc = "{coupling}"', "", "[dynamics]"]
    for k in range(1, m + 1):
        left, right = (k - 2) % m + 1, k % m + 1
        if m == 1:
            spring = ""
        elif m == 2:
            spring = f" - kc*(q{k} - q{left})"
        else:
            spring = f" - kc*(2*q{k} - q{left} - q{right})"
        lines += [f'q{k} = "p{k}"', f'p{k} = "-q{k} - q{k}**3 - c*p{k}{spring}"']
    return "\n".join(lines) + "\n"


def platoon(m: int, kp: str = "1", kd: str = "2") -> str:
    """A chain of ``m`` vehicles, each with a PD law on its spacing to the one ahead (the first follows
    the leader), and a cubic drag; the errors ``e_k`` (spacing) and ``w_k`` (speed) are the states."""
    if m < 1:
        raise ValueError(f"platoon: m must be at least 1, got {m}")
    names = [v for k in range(1, m + 1) for v in (f"e{k}", f"w{k}")]
    lines = [f"# A platoon of {m} vehicles: spacing and speed errors ({2 * m} states).", "[model]",
             f'name = "platoon of {m} vehicles"', f"states = {_states(names)}", "", "[parameters]",
             f'kp = "{kp}"', f'kd = "{kd}"', "", "[dynamics]"]
    for k in range(1, m + 1):
        # e_k' = w_(k-1) - w_k (w_0 = 0: the leader), w_k' = kp e_k + kd e_k' - w_k^3: each vehicle's
        # linear block s^2 + kd s + kp is Hurwitz, the drag dissipates, the chain is a cascade
        rate = f"w{k - 1} - w{k}" if k > 1 else f"-w{k}"
        lines += [f'e{k} = "{rate}"', f'w{k} = "kp*e{k} + kd*({rate}) - w{k}**3"']
    return "\n".join(lines) + "\n"


def swarm(m: int, damping: str = "1", coupling: str = "0.2") -> str:
    """``m`` damped Duffing oscillators (as in :func:`ring`), each pulled by a linear spring towards the
    mean position of all the others (all-to-all, mean-field coupling of total stiffness ``kc``);
    ``n = 2 m`` states (``m >= 2``). GAS (the energy ``sum p_k^2/2 + q_k^2/2 + q_k^4/4`` plus the
    coupling springs' decreases), and every position reads every other: the interaction graph's
    cliques are as large as the network."""
    if m < 2:
        raise ValueError(f"swarm: m must be at least 2, got {m}")
    names = [v for k in range(1, m + 1) for v in (f"q{k}", f"p{k}")]
    lines = [f"# {m} damped oscillators with cubic springs, coupled all-to-all to their mean ({2 * m} states).",
             "[model]", f'name = "swarm of {m} Duffing oscillators"', f"states = {_states(names)}", "",
             "[parameters]", f'c = "{damping}"', f'kc = "{coupling}"', "", "[dynamics]"]
    for k in range(1, m + 1):
        others = " + ".join(f"q{j}" for j in range(1, m + 1) if j != k)
        mean = f"({others})/{m - 1}" if m > 2 else others
        lines += [f'q{k} = "p{k}"', f'p{k} = "-q{k} - q{k}**3 - c*p{k} - kc*(q{k} - {mean})"']
    return "\n".join(lines) + "\n"


def grid(m: int, damping: str = "1", susceptance: str = "1") -> str:
    """``m`` generators on a ring of lossless lines (swing equations), angles relative to generator
    ``m``; ``n = 2 m - 1`` states (``m >= 2``)."""
    if m < 2:
        raise ValueError(f"grid: m must be at least 2, got {m}")
    names = [f"d{k}" for k in range(1, m)] + [f"w{k}" for k in range(1, m + 1)]

    def angle(k: int) -> str:
        return "0" if k == m else f"d{k}"

    def flow(k: int, j: int) -> str:
        a, b = angle(k), angle(j)
        if b == "0":
            return f"sin({a})"
        if a == "0":
            return f"sin(-{b})"
        return f"sin({a} - {b})"

    lines = [f"# {m} generators on a ring of lossless lines ({2 * m - 1} states, swing equations).", "[model]",
             f'name = "ring grid of {m} generators"', f"states = {_states(names)}", "", "[parameters]",
             f'd = "{damping}"', f'b = "{susceptance}"', "", "[dynamics]"]
    for k in range(1, m):
        lines.append(f'd{k} = "w{k} - w{m}"')
    for k in range(1, m + 1):
        neighbours = sorted({(k - 2) % m + 1, k % m + 1} - {k})
        lines.append(f'w{k} = "-d*w{k} - b*(' + " + ".join(flow(k, j) for j in neighbours) + ')"')
    lines += ["", "[domain]"] + [f"d{k} = [-1.5, 1.5]" for k in range(1, m)] + \
        [f"w{k} = [-1, 1]" for k in range(1, m + 1)]
    return "\n".join(lines) + "\n"


def coupled_pairs(m: int) -> str:
    """LyZNet's 10-state example (``examples/models/lyznet-10d.toml``) grown to ``m`` damped 2-state
    oscillators on a ring, each driven by the square of its predecessor's first state
    (``x_a' = -x_a + x_b/2 - x_p^2/10``): ``n = 2 m`` states, locally exponentially stable, not
    globally (the quadratic couplings send large states to infinity), so this family is for ``roa``
    on the domain ``[-1, 1]^n`` (LyZNet's)."""
    if m < 1:
        raise ValueError(f"coupled_pairs: m must be at least 1, got {m}")
    names = [f"x{k}" for k in range(1, 2 * m + 1)]
    lines = [f"# {m} coupled damped oscillators on a ring, LyZNet's 10-state example grown ({2 * m} states).",
             "[model]", f'name = "{m} coupled pairs"', f"states = {_states(names)}", "", "[dynamics]"]
    for k in range(m):
        a, b, p = 2 * k + 1, 2 * k + 2, 2 * ((k - 1) % m) + 1
        drive = f" - 0.1*x{p}**2" if m > 1 else ""
        lines += [f'x{a} = "-x{a} + 0.5*x{b}{drive}"', f'x{b} = "-0.5*x{a} - x{b}"']
    lines += ["", "[domain]"] + [f"{s} = [-1, 1]" for s in names]
    return "\n".join(lines) + "\n"


def chain(m: int) -> str:
    """``m`` damped second-order blocks in a chain, each driven by the square of the previous block's
    position (``y_k' = -x_k - y_k + x_(k-1)^2``): a cascade (each block reads only the one before), GAS,
    whose quadratic couplings no linear comparison system of the vector form bounds; ``n = 2 m`` states.
    The cascade form's family (``lyapunov_cascade``)."""
    if m < 1:
        raise ValueError(f"chain: m must be at least 1, got {m}")
    names = [v for k in range(1, m + 1) for v in (f"x{k}", f"y{k}")]
    lines = [f"# A chain of {m} damped blocks, each driven by the square of the previous one ({2 * m} states).",
             "[model]", f'name = "chain of {m} driven blocks"', f"states = {_states(names)}", "", "[dynamics]"]
    for k in range(1, m + 1):
        drive = f" + x{k - 1}**2" if k > 1 else ""
        lines += [f'x{k} = "y{k}"', f'y{k} = "-x{k} - y{k}{drive}"']
    return "\n".join(lines) + "\n"


FAMILIES = {"ring": ring, "platoon": platoon, "grid": grid, "pairs": coupled_pairs, "swarm": swarm, "chain": chain}
