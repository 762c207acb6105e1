#!/usr/bin/env python
"""Per-solve time on every case of the paper (examples/paper/*.yaml), against
SciPy SLSQP (the paper's method) and CVXPY with Clarabel, in one process.

Every method solves the same small-displacement problem, written from the
same assembled data (``jointplay.assembly``): the unknowns x of every moving
body, the clearance cones ``|A_i x| + B_i x <= r_i``, the rigid rows
``E x = 0`` and the loads' work ``g @ x``.

* ``jointplay``: ``jointplay.solve(model)``, cold: assembly, free motions,
  Clarabel, polishing, certificate and the ``Result`` (what a user pays);
* ``warm``: ``Workspace.solve()`` again on one workspace (a study's cost);
* ``SLSQP``: ``scipy.optimize.minimize(method="SLSQP")`` on the paper's
  quadratic form of the limits, ``r_i^2 - |A_i x|^2 >= 0`` (and
  ``r_i - B_i x >= 0`` for a one-sided limit), analytic gradients, from x = 0,
  ``ftol=1e-15``;
* ``CVXPY``: the cone program from cvxpy atoms, built and solved by Clarabel
  at jointplay's tolerance (the build is part of each timed solve).

The table prints the median ms per solve, each method's ratio to jointplay's
cold solve, and how far its answer is from jointplay's: the loads' potential
energy (relative) and the joints' translations at their centres (mm). Free
motions that no load drives (a shaft's spin) leave SLSQP and CVXPY with any
value there; joint-centre translations on the paper's cases do not see them.

Run from the repository root: ``python benchmarks/bench_cases.py [--repeat N]``.
Timing is informative: the script exits 0 whatever the numbers are.
"""

from __future__ import annotations

import argparse
import statistics
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import minimize

import jointplay
from bench_paper import per_solve_times
from jointplay.assembly import Assembly, assemble
from jointplay.numerics.linalg import dense
from jointplay.solver.solve import Workspace

try:  # CVXPY is the optional "bench" extra
    import cvxpy as cp
except ImportError:  # pragma: no cover - reported in the table
    cp = None

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "examples" / "paper"


def median_ms(fn: Callable[[], object], repeat: int, warmup: int = 3) -> float:
    return 1e3 * statistics.median(per_solve_times(fn, repeat, warmup))


def cones(asm: Assembly) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """(A_i, B_i, r_i) per clearance cone, dense."""
    st = asm.stack
    A, B = dense(st.A), dense(st.B)
    return [
        (A[st.start[i] : st.start[i] + st.k[i]], B[i], float(st.r[i])) for i in range(len(st.k))
    ]


def slsqp(asm: Assembly) -> np.ndarray:
    """The paper's method on the assembled problem: SQP from x = 0."""
    cs = cones(asm)
    E = dense(asm.E)
    g = asm.g
    constraints: list[dict[str, Any]] = []
    for A, B, r in cs:
        if np.any(B):
            constraints.append(
                {"type": "ineq", "fun": lambda x, B=B, r=r: r - B @ x, "jac": lambda x, B=B: -B}
            )
        if A.shape[0]:
            if np.any(B):
                constraints.append(
                    {
                        "type": "ineq",
                        "fun": lambda x, A=A, B=B, r=r: (r - B @ x) ** 2 - (A @ x) @ (A @ x),
                        "jac": lambda x, A=A, B=B, r=r: -2 * (r - B @ x) * B - 2 * (A.T @ (A @ x)),
                    }
                )
            else:
                constraints.append(
                    {
                        "type": "ineq",
                        "fun": lambda x, A=A, r=r: r * r - (A @ x) @ (A @ x),
                        "jac": lambda x, A=A: -2 * (A.T @ (A @ x)),
                    }
                )
    if len(E):
        constraints.append({"type": "eq", "fun": lambda x: E @ x, "jac": lambda x: E})
    out = minimize(
        lambda x: -g @ x,
        np.zeros(asm.m),
        jac=lambda x: -g,
        method="SLSQP",
        constraints=constraints,
        options={"ftol": 1e-15, "maxiter": 10000},
    )
    return np.asarray(out.x)


def cvxpy_build_and_solve(asm: Assembly) -> np.ndarray:
    x = cp.Variable(asm.m)
    cons = []
    for A, B, r in cones(asm):
        if A.shape[0]:
            cons.append(cp.SOC(r - B @ x, A @ x))
        else:
            cons.append(B @ x <= r)
    E = dense(asm.E)
    if len(E):
        cons.append(E @ x == 0)
    problem = cp.Problem(cp.Minimize(-asm.g @ x), cons)
    problem.solve(
        solver="CLARABEL", tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10, max_iter=200
    )
    return np.asarray(x.value)


def joint_translations(asm: Assembly, x: np.ndarray) -> np.ndarray:
    return np.concatenate([G.apply(x)[:3] for G in asm.G])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=30, help="timed solves per method")
    args = parser.parse_args(argv)

    print("Per-solve time on the paper's cases (median ms; ratio = method / jointplay cold)")
    header = (
        f"{'case':<22}{'jointplay':>10}{'warm':>8}{'SLSQP':>9}{'ratio':>7}"
        f"{'dE':>9}{'dmm':>9}{'CVXPY':>9}{'ratio':>7}{'dE':>9}{'dmm':>9}"
    )
    print(header)
    print("-" * len(header))
    for path in sorted(PAPER.glob("*.yaml")):
        model = jointplay.load(path)
        asm = assemble(model)
        result = jointplay.solve(model)
        result.check()
        ws = Workspace(asm)
        ws.solve()
        x_ref = asm.unknowns_of(result.bodies)
        energy = -float(asm.g @ x_ref)
        t_ref = joint_translations(asm, x_ref)

        t_cold = median_ms(lambda model=model: jointplay.solve(model), args.repeat)
        t_warm = median_ms(lambda ws=ws: ws.solve(), args.repeat)
        t_sl = median_ms(lambda asm=asm: slsqp(asm), max(3, args.repeat // 3), warmup=1)
        x_sl = slsqp(asm)

        def gaps(
            x: np.ndarray, asm: Assembly = asm, energy: float = energy, t_ref: np.ndarray = t_ref
        ) -> tuple[float, float]:
            dE = abs(-float(asm.g @ x) - energy) / max(abs(energy), 1e-300)
            dmm = float(np.max(np.abs(joint_translations(asm, x) - t_ref)))
            return dE, dmm

        dE_sl, dmm_sl = gaps(x_sl)
        row = (
            f"{path.stem:<22}{t_cold:>10.3f}{t_warm:>8.3f}{t_sl:>9.3f}{t_sl / t_cold:>7.1f}"
            f"{dE_sl:>9.1e}{dmm_sl:>9.1e}"
        )
        if cp is not None:
            t_cv = median_ms(lambda asm=asm: cvxpy_build_and_solve(asm), args.repeat, warmup=1)
            dE_cv, dmm_cv = gaps(cvxpy_build_and_solve(asm))
            row += f"{t_cv:>9.3f}{t_cv / t_cold:>7.1f}{dE_cv:>9.1e}{dmm_cv:>9.1e}"
        else:
            row += "   (cvxpy not installed: pip install '.[bench]')"
        print(row)
    print(
        "dE: relative difference of the loads' potential energy from jointplay's; "
        "dmm: largest difference of a joint's translation at its centre (mm)."
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
