"""Published figures of peer tools on the example model files (``examples/models/*.toml``).

``ANCHORS`` maps a model file's stem (``van-der-pol-reversed`` for
``examples/models/van-der-pol-reversed.toml``) to the figures a peer tool published for the same
system: which tool, what was measured, the number, its unit and where it was printed. Only
figures read in a source are listed; an empty list means none was found (the model file's own
comments then give what is known exactly, e.g. the linear examples' worst-case bounds).

Where the figures come from, and how far to trust them:

- LyZNet (Liu, Meng, Fitzsimmons, Zhou, HSCC 2024): the numbers are those of the expected-output
  logs the LyZNet repository ships next to the paper's example scripts (``examples/hscc24/*.txt``;
  its README calls them the expected output of the paper's examples). The paper's own text could
  not be read here, so a figure printed in the paper may be rounded differently (e.g. 94.1 % and
  94.8 % for 94.10 % and 94.78 %). Times are LyZNet's, on the authors' machine; the SOS Lyapunov
  function was computed beforehand and LyZNet only *verifies* it (the 9.77 s), and the neural
  figures split into training (494 s) and verification (973 s), about 1,470 s together.
  "Share of the ROA" is LyZNet's volume ratio: of 90,000 random samples of the domain box, the
  ones in the verified sublevel set divided by the ones whose simulation converged.
- Fossil (Edwards, Peruffo, Abate, HSCC 2024): Table 2 of the paper compares Fossil 1.0 and 2.0
  over 10 runs per benchmark. The numbers here are the repeatability artifact's output table
  ``results/fossil_comparison.csv`` (and ``results/tool_paper_tab.csv`` for Table 3) in the Fossil
  repository; the printed paper could not be read here. The Fossil 1.0 columns agree with an
  earlier draft of the table (``experiments/comparison.tex``); the Fossil 2.0 columns differ from
  that draft (noted per entry), so treat them as indicative. Times are wall-clock seconds of the
  whole counterexample-guided synthesis (learn and verify), on a domain that is a ball, not the
  model file's box. The barrier rows (Barr1, Barr3 in Table 2; HighOrd8, Table 3 benchmark 4) are
  on FOSSIL's own sets, which the model files copy (their domain is FOSSIL's too, except HighOrd4/6,
  whose ball domain the files widen to its bounding box; neither is published).
- Drake: the cubic example asserts its certified level; that is the figure.
"""

from __future__ import annotations

from typing import TypedDict


class Anchor(TypedDict):
    """One published figure: the peer tool, what it measures, the number, its unit, the source."""

    tool: str
    figure: str
    value: float
    unit: str
    source: str


_LYZNET_PAPER = (
    "J. Liu, Y. Meng, M. Fitzsimmons, R. Zhou, 'LyZNet: A Lightweight Python Tool for Learning and "
    "Verifying Neural Lyapunov Functions and Regions of Attraction', HSCC 2024 "
    "(doi:10.1145/3641513.3650134, arXiv:2403.10013), Van der Pol example"
)
_LYZNET_REPO = (
    "LyZNet repository (https://git.uwaterloo.ca/hybrid-systems-lab/lyznet), read from the GitHub "
    "mirror https://github.com/Sorachat1997/lyznet at commit "
    "fb6e4f19299d06e5bd15f897ec2b0a918aab1edc"
)
_VDP1_LOG = (
    f"{_LYZNET_PAPER} (mu = 1); expected-output log examples/hscc24/ex1a_van_der_pol_mu_1.0.txt "
    f"of the {_LYZNET_REPO}"
)
_VDP3_LOG = (
    f"{_LYZNET_PAPER} (mu = 3); expected-output log examples/hscc24/ex1b_van_der_pol_mu_3.0.txt "
    f"of the {_LYZNET_REPO}"
)
_FOSSIL_PAPER = (
    "A. Edwards, A. Peruffo, A. Abate, 'Fossil 2.0: Formal Certificate Synthesis for the "
    "Verification and Control of Dynamical Models', HSCC 2024 (arXiv:2311.09793)"
)
_FOSSIL_REPO = (
    "repeatability output of https://github.com/oxford-oxcav/fossil at commit "
    "50fe6a0246e972f0fd2d9d721dceeadca7d3181f"
)
_FOSSIL_TABLE2 = (
    f"{_FOSSIL_PAPER}, Table 2 (Fossil 1.0 vs 2.0, 10 runs); {_FOSSIL_REPO}, "
    "results/fossil_comparison.csv"
)
_FOSSIL_TABLE3 = (
    f"{_FOSSIL_PAPER}, Table 3, benchmark 1 (3 states, stability; run first by the artifact's "
    f"run_hscc_experiments.sh, i.e. experiments/benchmarks/lyap/non_poly_2.py); {_FOSSIL_REPO}, "
    "results/tool_paper_tab.csv"
)
_FOSSIL_BARRIER_TABLE2 = (
    f"{_FOSSIL_PAPER}, Table 2 (Fossil 1.0 vs 2.0, 10 runs, safety rows); {_FOSSIL_REPO}, "
    "results/fossil_comparison.csv (results/fossil_comparison.tex, the file the model files cite); "
    "the sets are those of the model file (FOSSIL's experiments/benchmarks/barrier/)"
)
_FOSSIL_HIGHORD8 = (
    f"{_FOSSIL_PAPER}, Table 3, benchmark 4 (8 states, safety: HighOrd8, "
    f"experiments/benchmarks/barrier/hi_ord_8.py, rectangles as in the model file); {_FOSSIL_REPO}, "
    "results/tool_paper_tab.csv row 4 (results/tool_paper_tab.tex, the file the model file cites); "
    "the parenthesised figures beside the times there (7.48, 31.64, 43.15) are not read here"
)
_FOSSIL2_DRAFT_NONPOLY0 = " (an earlier draft, experiments/comparison.tex, prints max 1.54 s)"
_FOSSIL2_DRAFT_POLY2 = (
    " (an earlier draft, experiments/comparison.tex, prints Fossil 2.0 at min 0.08 s, mean 4.77 s, "
    "max 6.50 s, success 100 %)"
)
_DRAKE_CUBIC = (
    "Drake (https://github.com/RobotLocomotion/drake), examples/cubic_polynomial/"
    "region_of_attraction.cc: maximizes rho with {x^2 < rho} in the region of attraction and "
    "asserts |rho - 1| < 1e-6 (C++ version of the MATLAB example CubicPolynomialExample.m)"
)

#: the power system's figures are the issue's quotation (its LyZNet log could not be read here)
_POWER_QUOTE = "issue 31 of this project, quoting LyZNet (Liu, Meng, Fitzsimmons, Zhou, HSCC 2024), two-machine power system"

ANCHORS: dict[str, list[Anchor]] = {
    "van-der-pol-reversed": [
        {
            "tool": "LyZNet",
            "figure": "share of the true ROA (within the domain box) covered by the verified "
            "sublevel set of a degree-6 SOS Lyapunov function",
            "value": 94.10,
            "unit": "%",
            "source": _VDP1_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "time to verify the (precomputed) degree-6 SOS Lyapunov function's ROA "
            "with dReal",
            "value": 9.774,
            "unit": "s",
            "source": _VDP1_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "share of the true ROA (within the domain box) covered by the verified "
            "sublevel set of the neural Lyapunov function (Zubov PINN, 2 x 30 tanh)",
            "value": 94.78,
            "unit": "%",
            "source": _VDP1_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "training time of the neural Lyapunov function (20 epochs, 300,000 "
            "collocation points, 3,000 simulated samples)",
            "value": 494.24,
            "unit": "s",
            "source": _VDP1_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "verification time of the neural Lyapunov function with dReal",
            "value": 973.19,
            "unit": "s",
            "source": _VDP1_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "largest verified level c of x^T P x <= c, P = [[3/2, -1/2], [-1/2, 1]] "
            "(A^T P + P A = -I), by linearization (local)",
            "value": 0.2978965640068054,
            "unit": "level of x^T P x",
            "source": _VDP1_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "largest verified ROA level c of x^T P x <= c, P = [[3/2, -1/2], [-1/2, 1]], "
            "by reach-and-stay on the domain box (quadratic verifier, 0.24 s)",
            "value": 2.304154939650971,
            "unit": "level of x^T P x",
            "source": _VDP1_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "samples of the domain box (of 90,000 random) whose simulation converged "
            "to 0, i.e. the true ROA's share of the box is 39.1 %",
            "value": 35230,
            "unit": "samples of 90000",
            "source": _VDP1_LOG,
        },
    ],
    "van-der-pol-reversed-mu3": [
        {
            "tool": "LyZNet",
            "figure": "share of the true ROA (within the domain box) covered by the verified "
            "sublevel set of a degree-6 SOS Lyapunov function",
            "value": 70.93,
            "unit": "%",
            "source": _VDP3_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "time to verify the (precomputed) degree-6 SOS Lyapunov function's ROA "
            "with dReal",
            "value": 7.628,
            "unit": "s",
            "source": _VDP3_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "share of the true ROA (within the domain box) covered by the verified "
            "sublevel set of the neural Lyapunov function (Zubov PINN, 2 x 30 tanh)",
            "value": 85.21,
            "unit": "%",
            "source": _VDP3_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "training time of the neural Lyapunov function (20 epochs, 300,000 "
            "collocation points, 3,000 simulated samples)",
            "value": 502.96,
            "unit": "s",
            "source": _VDP3_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "verification time of the neural Lyapunov function with dReal",
            "value": 442.01,
            "unit": "s",
            "source": _VDP3_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "largest verified level c of x^T P x <= c, P = [[11/6, -1/2], [-1/2, 1/3]] "
            "(A^T P + P A = -I), by linearization (local)",
            "value": 0.07637590169906616,
            "unit": "level of x^T P x",
            "source": _VDP3_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "largest verified ROA level c of x^T P x <= c, "
            "P = [[11/6, -1/2], [-1/2, 1/3]], by reach-and-stay on the domain box "
            "(quadratic verifier, 0.26 s)",
            "value": 1.2581241607122706,
            "unit": "level of x^T P x",
            "source": _VDP3_LOG,
        },
        {
            "tool": "LyZNet",
            "figure": "samples of the domain box (of 90,000 random) whose simulation converged "
            "to 0, i.e. the true ROA's share of the box is 28.6 %",
            "value": 25747,
            "unit": "samples of 90000",
            "source": _VDP3_LOG,
        },
    ],
    "ahmadi-no-polynomial-lyapunov": [
        {
            "tool": "Fossil 2.0",
            "figure": "mean synthesis time of a neural Lyapunov function for benchmark NonPoly0 "
            "(this field) on the unit disc minus a radius-0.01 disc",
            "value": 0.16,
            "unit": "s",
            "source": _FOSSIL_TABLE2,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "minimum synthesis time over 10 runs, NonPoly0",
            "value": 0.01,
            "unit": "s",
            "source": _FOSSIL_TABLE2,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "maximum synthesis time over 10 runs, NonPoly0",
            "value": 1.47,
            "unit": "s",
            "source": _FOSSIL_TABLE2 + _FOSSIL2_DRAFT_NONPOLY0,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "share of 10 runs that returned a verified certificate, NonPoly0",
            "value": 100,
            "unit": "%",
            "source": _FOSSIL_TABLE2,
        },
        {
            "tool": "Fossil 1.0",
            "figure": "mean synthesis time of a neural Lyapunov function, NonPoly0",
            "value": 0.21,
            "unit": "s",
            "source": _FOSSIL_TABLE2,
        },
        {
            "tool": "Fossil 1.0",
            "figure": "minimum synthesis time over 10 runs, NonPoly0",
            "value": 0.04,
            "unit": "s",
            "source": _FOSSIL_TABLE2,
        },
        {
            "tool": "Fossil 1.0",
            "figure": "maximum synthesis time over 10 runs, NonPoly0",
            "value": 1.58,
            "unit": "s",
            "source": _FOSSIL_TABLE2,
        },
        {
            "tool": "Fossil 1.0",
            "figure": "share of 10 runs that returned a verified certificate, NonPoly0",
            "value": 100,
            "unit": "%",
            "source": _FOSSIL_TABLE2,
        },
    ],
    "fossil-poly2": [
        {
            "tool": "Fossil 2.0",
            "figure": "mean synthesis time of a neural Lyapunov function for benchmark Poly2 on "
            "the disc of radius 5 minus a radius-0.01 disc",
            "value": 5.64,
            "unit": "s",
            "source": _FOSSIL_TABLE2 + _FOSSIL2_DRAFT_POLY2,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "minimum synthesis time over 10 runs, Poly2",
            "value": 0.01,
            "unit": "s",
            "source": _FOSSIL_TABLE2 + _FOSSIL2_DRAFT_POLY2,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "maximum synthesis time over 10 runs, Poly2",
            "value": 45.46,
            "unit": "s",
            "source": _FOSSIL_TABLE2 + _FOSSIL2_DRAFT_POLY2,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "share of 10 runs that returned a verified certificate, Poly2",
            "value": 90,
            "unit": "%",
            "source": _FOSSIL_TABLE2 + _FOSSIL2_DRAFT_POLY2,
        },
        {
            "tool": "Fossil 1.0",
            "figure": "mean synthesis time of a neural Lyapunov function, Poly2",
            "value": 11.71,
            "unit": "s",
            "source": _FOSSIL_TABLE2,
        },
        {
            "tool": "Fossil 1.0",
            "figure": "minimum synthesis time over 10 runs, Poly2",
            "value": 0.35,
            "unit": "s",
            "source": _FOSSIL_TABLE2,
        },
        {
            "tool": "Fossil 1.0",
            "figure": "maximum synthesis time over 10 runs, Poly2",
            "value": 70.39,
            "unit": "s",
            "source": _FOSSIL_TABLE2,
        },
        {
            "tool": "Fossil 1.0",
            "figure": "share of 10 runs that returned a verified certificate, Poly2",
            "value": 90,
            "unit": "%",
            "source": _FOSSIL_TABLE2,
        },
    ],
    "fossil-nonpoly2": [
        {
            "tool": "Fossil 2.0",
            "figure": "mean synthesis time of a neural Lyapunov function (10 square-activated "
            "neurons) on the ball of radius 3 minus a radius-0.01 ball",
            "value": 0.45,
            "unit": "s",
            "source": _FOSSIL_TABLE3,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "minimum synthesis time over 10 runs",
            "value": 0.18,
            "unit": "s",
            "source": _FOSSIL_TABLE3,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "maximum synthesis time over 10 runs",
            "value": 1.23,
            "unit": "s",
            "source": _FOSSIL_TABLE3,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "share of 10 runs that returned a verified certificate",
            "value": 100,
            "unit": "%",
            "source": _FOSSIL_TABLE3,
        },
    ],
    "drake-cubic-polynomial": [
        {
            "tool": "Drake",
            "figure": "certified level rho of V = x^2 ({V < rho} inside the ROA); the exact ROA "
            "is (-1, 1), so rho = 1 is tight",
            "value": 1.0,
            "unit": "level of V = x**2",
            "source": _DRAKE_CUBIC,
        },
    ],
    "fossil-barr1": [
        {
            "tool": "Fossil 2.0",
            "figure": "mean synthesis time of a neural barrier certificate for benchmark Barr1 (learn and verify)",
            "value": 7.11,
            "unit": "s",
            "source": _FOSSIL_BARRIER_TABLE2,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "minimum synthesis time over 10 runs, Barr1",
            "value": 1.6,
            "unit": "s",
            "source": _FOSSIL_BARRIER_TABLE2,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "maximum synthesis time over 10 runs, Barr1",
            "value": 13.05,
            "unit": "s",
            "source": _FOSSIL_BARRIER_TABLE2,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "share of 10 runs that returned a verified certificate, Barr1",
            "value": 100,
            "unit": "%",
            "source": _FOSSIL_BARRIER_TABLE2,
        },
        {
            "tool": "Fossil 1.0",
            "figure": "mean synthesis time of a neural barrier certificate, Barr1",
            "value": 100.17,
            "unit": "s",
            "source": _FOSSIL_BARRIER_TABLE2,
        },
        {
            "tool": "Fossil 1.0",
            "figure": "share of 10 runs that returned a verified certificate, Barr1",
            "value": 10,
            "unit": "%",
            "source": _FOSSIL_BARRIER_TABLE2,
        },
    ],
    "fossil-barr3": [
        {
            "tool": "Fossil 2.0",
            "figure": "mean synthesis time of a neural barrier certificate for benchmark Barr3 (learn and verify)",
            "value": 29.35,
            "unit": "s",
            "source": _FOSSIL_BARRIER_TABLE2,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "minimum synthesis time over 10 runs, Barr3",
            "value": 13.42,
            "unit": "s",
            "source": _FOSSIL_BARRIER_TABLE2,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "maximum synthesis time over 10 runs, Barr3",
            "value": 84.55,
            "unit": "s",
            "source": _FOSSIL_BARRIER_TABLE2,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "share of 10 runs that returned a verified certificate, Barr3",
            "value": 100,
            "unit": "%",
            "source": _FOSSIL_BARRIER_TABLE2,
        },
        {
            "tool": "Fossil 1.0",
            "figure": "mean synthesis time of a neural barrier certificate, Barr3",
            "value": 101.72,
            "unit": "s",
            "source": _FOSSIL_BARRIER_TABLE2,
        },
        {
            "tool": "Fossil 1.0",
            "figure": "share of 10 runs that returned a verified certificate, Barr3",
            "value": 50,
            "unit": "%",
            "source": _FOSSIL_BARRIER_TABLE2,
        },
    ],
    "fossil-highord8": [
        {
            "tool": "Fossil 2.0",
            "figure": "mean synthesis time of a neural barrier certificate for HighOrd8 (learn and verify)",
            "value": 124.29,
            "unit": "s",
            "source": _FOSSIL_HIGHORD8,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "minimum synthesis time over the runs, HighOrd8",
            "value": 31.36,
            "unit": "s",
            "source": _FOSSIL_HIGHORD8,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "maximum synthesis time over the runs, HighOrd8",
            "value": 172.47,
            "unit": "s",
            "source": _FOSSIL_HIGHORD8,
        },
        {
            "tool": "Fossil 2.0",
            "figure": "share of the runs that returned a verified certificate, HighOrd8",
            "value": 70,
            "unit": "%",
            "source": _FOSSIL_HIGHORD8,
        },
    ],
    # not among Fossil 2.0's published runs (the model files' comments)
    "fossil-highord4": [],
    "fossil-highord6": [],
    "disturbed-tube": [],
    "reachable-spiral": [],
    "paper-tube": [],
    "fossil-poly1": [],
    "sosdemo2-rational": [],
    "sriram-4d": [],
    "unstable-van-der-pol": [],
    "linear-disturbed-l1": [],
    "linear-scalar-disturbed": [],
    "lyznet-10d": [],
    # LyZNet's two-machine power system (examples/ex2_two_machine_power.py in the LyZNet repository, whose
    # equations and domain the model file copies). Its expected-output log was not among the stored
    # material: these four figures are as issue 31 quotes them, not read in a LyZNet source here.
    "recast-power-two-machine": [
        {"tool": "LyZNet", "figure": "share of the simulated ROA covered by the SOS Lyapunov function's verified "
         "sublevel set (as quoted in issue 31)", "value": 18.5, "unit": "%", "source": _POWER_QUOTE},
        {"tool": "LyZNet", "figure": "share of the simulated ROA covered by the neural Lyapunov function's verified "
         "sublevel set (as quoted in issue 31)", "value": 82.3, "unit": "%", "source": _POWER_QUOTE},
        {"tool": "LyZNet", "figure": "dReal verification of the neural Lyapunov function (as quoted in issue 31)",
         "value": 3375, "unit": "s", "source": _POWER_QUOTE},
        {"tool": "LyZNet", "figure": "training of the neural Lyapunov function (as quoted in issue 31)",
         "value": 473, "unit": "s", "source": _POWER_QUOTE},
    ],
}
