"""Where chaospy fits the surrogate build, measured: the basis and the design against ours.

Run: ``python benchmarks/bench_chaospy.py [--no-write]``. Prints the figures and
rewrites the "chaospy in the surrogate build" section of ``benchmarks/RESULTS.md``.

The build (``models/offline/surrogate/build.py``) needs three things chaospy
also offers: an orthonormal basis for each input's distribution, a Latin
hypercube design, and the evaluation of the basis at many points. This script
runs both on the build's own sizes (1,200 design points in 5 inputs, degree 15)
and compares accuracy and time.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from collections.abc import Callable
from datetime import UTC, datetime

import chaospy
import numpy as np
from results_md import RESULTS, write_section

from models.offline.surrogate.build import latin_hypercube
from models.surrogate.basis import evaluate_univariate, stieltjes, uniform_recurrence

N_POINTS = 1200
DEGREE = 15
DIM = 5


def _best_ms(fn: Callable[[], object], repeats: int = 5) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return 1000.0 * best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    # a design's empirical measure: uniform in log delta-V, mapped to [-1, 1]
    x = 2.0 * (np.log(rng.uniform(20.0, 40.0, N_POINTS)) - np.log(20.0)) / np.log(2.0) - 1.0

    # 1. the recurrence of the uniform measure: ours against chaospy's Stieltjes
    (alpha, beta), _, _ = chaospy.stieltjes(DEGREE, chaospy.Uniform(-1.0, 1.0))
    a, b = uniform_recurrence(DEGREE)
    uni_err = max(
        float(np.max(np.abs(np.ravel(alpha)[: DEGREE + 1] - a))),
        float(np.max(np.abs(np.ravel(beta)[1 : DEGREE + 1] - b[1:]))),
    )
    # 2. the empirical measure of the design (the arbitrary PCE): ours is exact for
    # it; chaospy has no recurrence for a point set, its nearest is a Gaussian KDE
    # of the points, through its discretised Stieltjes
    t_ours = _best_ms(lambda: stieltjes(x, None, DEGREE))
    kde = chaospy.GaussianKDE(x)
    t0 = time.perf_counter()
    (ka, kb), _, _ = chaospy.discretized_stieltjes(DEGREE, kde)
    t_kde = 1000.0 * (time.perf_counter() - t0)
    oa, ob = stieltjes(x, None, DEGREE)
    kde_diff = float(np.max(np.abs(np.ravel(ka)[: DEGREE + 1] - oa)))
    # 3. orthonormality on the design itself: ours to round-off, KDE's not
    p_ours = evaluate_univariate(x, (oa, ob), DEGREE)
    p_kde = evaluate_univariate(x, (np.ravel(ka)[: DEGREE + 1], np.ravel(kb)[: DEGREE + 1]), DEGREE)
    gram = lambda p: float(np.max(np.abs(p.T @ p / x.size - np.eye(DEGREE + 1))))  # noqa: E731
    # 4. the Latin hypercube: ours (seeded Generator per family) against chaospy's
    t_lhs_ours = _best_ms(lambda: latin_hypercube(N_POINTS, DIM, np.random.default_rng(1)))
    t_lhs_cp = _best_ms(lambda: chaospy.create_latin_hypercube_samples(N_POINTS, DIM))
    # 5. evaluating the basis at the design: ours (recurrence in numpy) against
    # chaospy's polynomial objects (numpoly)
    poly = chaospy.expansion.stieltjes(DEGREE, chaospy.Uniform(-1.0, 1.0), normed=True)
    t_eval_ours = _best_ms(lambda: evaluate_univariate(x, (a, b), DEGREE))
    t_eval_cp = _best_ms(lambda: poly(x))
    eval_diff = float(
        np.max(np.abs(np.asarray(poly(x)).T - evaluate_univariate(x, (a, b), DEGREE)))
    )

    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    lines = [
        "## chaospy in the surrogate build",
        "",
        f"`python benchmarks/bench_chaospy.py` ({now}, {platform.machine()}, {os.cpu_count()} "
        f"CPUs, Python {platform.python_version()}, chaospy {chaospy.__version__}); "
        f"{N_POINTS} design points, degree {DEGREE}, best of 5.",
        "",
        "| step | ours | chaospy | agreement |",
        "|---|---|---|---|",
        f"| recurrence of the uniform measure | `uniform_recurrence` | `stieltjes` | "
        f"max difference {uni_err:.1e} |",
        f"| recurrence of the design's empirical measure (arbitrary PCE) | {t_ours:.2f} ms, "
        f"orthonormal on the design to {gram(p_ours):.1e} | no routine for a point set; "
        f"Gaussian KDE + `discretized_stieltjes` {t_kde:.0f} ms, orthonormal on the design "
        f"to {gram(p_kde):.1e} | alpha differ by up to {kde_diff:.1e} |",
        f"| Latin hypercube, {N_POINTS} x {DIM} | {t_lhs_ours:.2f} ms (seeded Generator "
        f"per family) | {t_lhs_cp:.2f} ms (numpy's global state) | - |",
        f"| basis at the design, degree 0-{DEGREE} | {t_eval_ours:.2f} ms | "
        f"{t_eval_cp:.2f} ms (numpoly) | max difference {eval_diff:.1e} |",
        "",
        "The arbitrary PCE (reference paper section 2.5) needs polynomials orthonormal for the "
        "design's own empirical measure: chaospy builds recurrences for distributions (by "
        "quadrature), so its nearest is a kernel density estimate of the points, a different "
        "measure, not orthonormal on the design and far slower; the build keeps its discrete "
        "Stieltjes (and the tests check it against chaospy's on the uniform measure). "
        "chaospy's Latin hypercube draws from numpy's global random state, where the build "
        "needs one seeded generator per family so that parallel, resumed and single-family "
        "builds give the same bits; and a new design would change every shipped artifact "
        "for no gain in accuracy. The request path stays numpy-only either way.",
    ]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        write_section("chaospy-build", text, RESULTS)


if __name__ == "__main__":
    main()
