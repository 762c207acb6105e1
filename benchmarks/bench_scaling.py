#!/usr/bin/env python
"""Scaling with size: chains and closed loops of 10 to 10,000 bodies.

The mechanisms are ``jointplay.io.generate.tube_string``: segments coupled by a
spigot (revolute) and a dowel pin, with a batch of real plays (seeded).
``chain`` is the open string loaded at its free end (axial pull, torque);
``loops`` also rests every segment in a bearing of its own and loads each
one sideways, which closes a loop through the ground at every segment.
``bearing`` is ``jointplay.io.generate.bearing_chain``: shafts each in a
cylindrical bearing and coupled to the one before by a revolute joint with
axial play, one force across the axis on each; every shaft's spin is free
(as many free motions as bodies) and the axial positions tie.

Each (kind, size) runs in a fresh Python process, so that its peak memory is
its own. In it, after the model is built (pydantic validation, not timed as
a solve), the script times:

* ``assemble``: the model turned into sparse matrices;
* ``workspace``: free motions (the null space of the joints' rows);
* ``solve``: Clarabel, polishing on the active set, certificate;
* ``result``: the ``Result`` (every joint, contact and force);
* ``total``: the four together, what ``jointplay.solve(model)`` costs;
* ``Clarabel``: of ``solve``, the time inside Clarabel itself (making its
  solvers and their ``solve``), and how many cone programs it ran: what no
  work of ours on the rest of the solve can go below;

and reports the peak resident memory of the process (MB, ``ru_maxrss``) and
what the solve added to it after the model was built. With ``--cvxpy-max N``
(default 1000) CVXPY + Clarabel builds and solves the same cone program for
sizes up to N, in the same process, as a reference.

Targets: 1,000 bodies in at most 0.5 s; 10,000 in at most 6 s
and 2 GB; at most 12x per decade. Each is printed with its verdict.

Run from the repository root: ``python benchmarks/bench_scaling.py``
(``--sizes 10 100 1000 10000``). Timing is informative: exits 0.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from typing import Any

#: The targets: seconds per solve by size, peak MB at 10,000, growth per decade.
SECONDS_TARGET = {1000: 0.5, 10000: 6.0}
MB_TARGET = 2048.0
DECADE_TARGET = 12.0


class _ClarabelClock:
    """Time spent inside Clarabel: ``clarabel.DefaultSolver`` wrapped so
    that making a solver and each of its ``solve`` calls are timed (the
    library calls it through the module, so the wrapper sees every program)."""

    def __init__(self) -> None:
        import clarabel

        self.module = clarabel
        self.real = clarabel.DefaultSolver
        self.seconds = 0.0
        self.programs = 0

    def __enter__(self) -> _ClarabelClock:
        clock, real = self, self.real

        class Timed:
            def __init__(self, *args: Any) -> None:
                start = time.perf_counter()
                self._solver = real(*args)
                clock.seconds += time.perf_counter() - start

            def solve(self) -> Any:
                start = time.perf_counter()
                try:
                    return self._solver.solve()
                finally:
                    clock.seconds += time.perf_counter() - start
                    clock.programs += 1

            def __getattr__(self, name: str) -> Any:
                return getattr(self._solver, name)

        self.module.DefaultSolver = Timed
        return self

    def __exit__(self, *exc: object) -> None:
        self.module.DefaultSolver = self.real


def measure(kind: str, n: int, cvxpy: bool) -> dict[str, Any]:
    """One case, in this process (the child)."""
    import scipy.sparse as sp

    import jointplay
    from jointplay.assembly import assemble
    from jointplay.io.generate import bearing_chain, tube_string
    from jointplay.solver import pipeline as solver_module
    from jointplay.solver.solve import Workspace

    model = bearing_chain(n) if kind == "bearing" else tube_string(n, closed=(kind == "loops"))
    base_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    t0 = time.perf_counter()
    asm = assemble(model)
    asm.stack, asm.E  # noqa: B018 - built lazily; count them in the assembly
    t1 = time.perf_counter()
    ws = Workspace(asm)
    t2 = time.perf_counter()
    built = solver_module.build_result
    spent = [0.0]

    def timed_build(*args: Any, **kwargs: Any) -> jointplay.Result:
        start = time.perf_counter()
        out = built(*args, **kwargs)
        spent[0] = time.perf_counter() - start
        return out

    solver_module.build_result = timed_build
    with _ClarabelClock() as clarabel_clock:
        result = ws.solve()
    t3 = time.perf_counter()
    solver_module.build_result = built
    result.check()
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    out: dict[str, Any] = {
        "kind": kind,
        "bodies": n,
        "unknowns": asm.m,
        "cones": len(asm.balls),
        "assemble": t1 - t0,
        "workspace": t2 - t1,
        "solve": t3 - t2 - spent[0],
        "result": spent[0],
        "clarabel": clarabel_clock.seconds,
        "programs": clarabel_clock.programs,
        "total": t3 - t0,
        "peak_mb": peak_mb,
        "solve_mb": peak_mb - base_mb,
        "method": result.certificate.method,
        "feasibility_mm": result.certificate.feasibility_mm,
        "residual": result.equilibrium_residual,
    }
    if cvxpy:
        try:
            import cvxpy as cp
        except ImportError:
            return out
        st = asm.stack
        start = time.perf_counter()
        x = cp.Variable(asm.m)
        A, B = sp.csr_matrix(st.A), sp.csr_matrix(st.B)
        cons = [
            cp.SOC(st.r[i] - B[i] @ x, A[st.start[i] : st.start[i] + st.k[i]] @ x)
            if st.k[i]
            else B[i] @ x <= st.r[i]
            for i in range(len(st.k))
        ]
        if asm.E.shape[0]:
            cons.append(asm.E @ x == 0)
        problem = cp.Problem(cp.Minimize(-asm.g @ x), cons)
        problem.solve(solver="CLARABEL", tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10)
        out["cvxpy"] = time.perf_counter() - start
        x_ours = asm.unknowns_of(result.bodies)
        energy = -float(asm.g @ x_ours)
        out["cvxpy_dE"] = abs(-float(asm.g @ x.value) - energy) / abs(energy)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000, 10000])
    parser.add_argument("--kinds", nargs="+", default=["chain", "loops", "bearing"])
    parser.add_argument("--cvxpy-max", type=int, default=1000)
    parser.add_argument("--child", nargs=3, metavar=("KIND", "N", "CVXPY"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        kind, n, cvx = args.child
        print(json.dumps(measure(kind, int(n), cvx == "1")))
        return 0

    print("Scaling: time (s) per solve and memory (MB), one fresh process per row")
    header = (
        f"{'kind':<6}{'bodies':>7}{'unknowns':>9}{'assemble':>9}{'workspace':>10}{'solve':>8}"
        f"{'result':>8}{'total':>8}{'Clarabel':>13}{'x prev':>7}{'peak MB':>8}{'+MB':>7}"
        f"{'CVXPY':>8}{'ratio':>7}  method / check"
    )
    print(header)
    print("-" * len(header))
    for kind in args.kinds:
        previous: dict[str, Any] | None = None
        for n in args.sizes:
            cvx = "1" if n <= args.cvxpy_max else "0"
            proc = subprocess.run(
                [sys.executable, __file__, "--child", kind, str(n), cvx],
                capture_output=True,
                text=True,
                check=False,
            )
            if proc.returncode != 0:
                last = (proc.stderr.strip().splitlines() or ["?"])[-1]
                print(f"{kind:<6}{n:>7}  failed: {last}")
                continue
            row = json.loads(proc.stdout.strip().splitlines()[-1])
            ratio = row["total"] / previous["total"] if previous else None
            growth = "-" if ratio is None else f"{ratio:.1f}"
            programs = f"({row['programs']})"
            cv = (
                f"{row['cvxpy']:>8.3f}{row['cvxpy'] / row['total']:>7.1f}"
                if "cvxpy" in row
                else (f"{'-':>8}{'-':>7}")
            )
            print(
                f"{kind:<6}{n:>7}{row['unknowns']:>9}{row['assemble']:>9.3f}{row['workspace']:>10.3f}"
                f"{row['solve']:>8.3f}{row['result']:>8.3f}{row['total']:>8.3f}"
                f"{row['clarabel']:>8.3f}{programs:>5}{growth:>7}"
                f"{row['peak_mb']:>8.0f}{row['solve_mb']:>7.0f}{cv}"
                f"  {row['method']}, past {row['feasibility_mm']:.0e} mm,"
                f" residual {row['residual']:.0e}"
            )
            if n in SECONDS_TARGET:
                verdict = "meets" if row["total"] <= SECONDS_TARGET[n] else "misses"
                print(
                    f"{'':<13}{n:,} bodies: {row['total']:.3f} s, {verdict} the "
                    f"{SECONDS_TARGET[n]:g} s target"
                )
            if n == 10000:
                verdict = "meets" if row["peak_mb"] <= MB_TARGET else "misses"
                print(f"{'':<13}{row['peak_mb']:,.0f} MB at its peak, {verdict} the 2 GB target")
            if ratio is not None and n == 10 * previous["bodies"]:
                verdict = "meets" if ratio <= DECADE_TARGET else "misses"
                print(
                    f"{'':<13}x {ratio:.1f} from {previous['bodies']:,}: "
                    f"{verdict} the {DECADE_TARGET:g}x per decade target"
                )
            previous = row
    print(
        "x prev: total time over the previous size's (10 for linear growth per decade). "
        "ratio: CVXPY + Clarabel (build + solve) over jointplay's total. Clarabel: of the "
        "solve, the seconds inside Clarabel (its programs in brackets)."
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
