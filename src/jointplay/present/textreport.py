"""The human-readable report of ``jointplay solve``: the paper's kinematic
vectorial sets per joint, and which contacts touch."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from rich.console import Console, Group
from rich.table import Table
from rich.text import Text

from jointplay.geometry import FloatArray, fmt_point
from jointplay.indeterminacy import Indeterminacy, over_steps
from jointplay.model.mechanism import Model
from jointplay.result import Result
from jointplay.settings import DEFAULT

if TYPE_CHECKING:  # the studies bring SciPy's statistics: a solve does not need them
    from jointplay.studies.contributions import ContributionsResult
    from jointplay.studies.envelope import EnvelopeResult
    from jointplay.studies.montecarlo import MonteCarloResult
    from jointplay.studies.sweep import SweepResult
    from jointplay.studies.tolerances import TolerancesResult


def _num(v: float, digits: int = 8) -> str:
    return f"{0.0 if abs(v) < 1e-300 else v: .{digits}e}"


def _vec(v: FloatArray, digits: int = 4) -> str:
    return "[" + ", ".join(f"{float(c) + 0.0:.{digits}g}" for c in v) + "]"


#: What every certified answer of a study proves.
CERTIFIED = (
    f"no contact past its play by {DEFAULT.feasibility_tolerance:g} of the largest play, "
    f"every body balanced to {DEFAULT.equilibrium_tolerance:g} of the largest force"
)

#: The width of a console that is not a terminal (a pipe, a file, a CI log):
#: wider than any line, so that no line is ever wrapped.
UNBROKEN = 1_000_000


def _fit(console: Console, *parts: Any) -> Group:
    """The parts laid out so that no number or name is broken across lines.

    A table's title goes on a line of its own (Rich wraps a title to the
    table's width), and each cell on one line. A table wider than the
    console closes up its padding; where it still does not fit, each row is
    printed as a list of "column: value" instead. Text wraps between words
    only; a console that is not a terminal is ``UNBROKEN`` wide, so nothing
    wraps there."""
    laid: list[Any] = []
    for part in parts:
        if not isinstance(part, Table):
            laid.append(part)
            continue
        if part.title:
            laid.append(Text(str(part.title)))
            part.title = None
        for column in part.columns:  # a cell is one line: a number or a name whole
            column.no_wrap, column.overflow = True, "fold"  # never '…': caught below
        wide = console.options.update_width(UNBROKEN)
        if console.measure(part, options=wide).maximum > console.width:
            part.collapse_padding = True  # one space between columns, not two
            if not _cells_whole(console, part):
                laid.append(_as_list(part))
                continue
        laid.append(part)
    return Group(*laid)


def _cells(table: Table) -> list[list[str]]:
    """The header and the cells of each column of ``table``, as plain text."""
    return [[str(c.header), *(str(cell) for cell in c.cells)] for c in table.columns]


def _cells_whole(console: Console, table: Table) -> bool:
    """Whether ``table`` at the console's width shows every cell on one line."""
    from collections import Counter

    lines = ["".join(s.text for s in line) for line in console.render_lines(table, pad=False)]
    cells = [cell.strip() for column in _cells(table) for cell in column]
    shown = Counter(word for line in lines for word in line.split())
    if Counter(word for cell in cells for word in cell.split()) - shown:
        return False  # a word cut in two
    text = "\n".join(lines)
    return all(cell in text for cell in cells if " " in cell)


def _as_list(table: Table) -> Text:
    """A table too wide for the console, a row a paragraph: its first cell,
    then "column: value" for each other cell that holds something (a row
    with no first cell continues the one above)."""
    headers, *rows = zip(*_cells(table), strict=True)
    lines = []
    for first, *rest in rows:
        named = [
            f"{h.strip()}: {v.strip()}" if h.strip() else v.strip()
            for h, v in zip(headers[1:], rest, strict=True)
            if v.strip()
        ]
        lines.append((f"{first.strip()}: " if first.strip() else "    ") + "; ".join(named))
    return Text("\n".join(lines))


def _xyz_table(title: str, leading: list[str]) -> Table:
    """A table of global X, Y, Z components after the ``leading`` columns."""
    table = Table(title=title, title_justify="left", show_edge=False)
    for name in leading:
        table.add_column(name)
    for axis in "XYZ":
        table.add_column(axis, justify="right")
    return table


def sobol_share(v: float, interval: Any) -> str:
    """A Sobol' index in percent with its interval, to one decimal each (an
    estimate's noise can take it below 0 or past 100: printed as it is)."""
    lo, hi = (float(x) for x in interval)
    return f"{percent(v)} [{percent(lo)}, {percent(hi)}]"


def percent(share: float) -> str:
    """A share in percent to one decimal; one that rounds to 0 is 0.0, not
    -0.0 (an estimate's noise about 0)."""
    return f"{round(100 * share, 1) + 0.0:.1f}"


#: The forces' sentence names this many joints at most (a large mechanism's
#: redundant loops run through thousands): the others are counted.
NAMED_JOINTS = 6


def indeterminacy_words(result: Result) -> str | None:
    """The forces' sentence where the touching contacts are statically
    indeterminate (``Result.indeterminate``), naming the joints that share
    the redundant load; None where the balance decides every force (the
    text and the report alike)."""
    return split_words(result.indeterminate)


def steps_split_words(found: Sequence[Indeterminacy], joints: Sequence[str]) -> str | None:
    """The forces' sentence of a study's steps (a sweep's, a motion's): at
    which of them the printed contact forces are a convention, and whose."""
    sentences = []
    # the steps split by the rule, then those the solver left as they were
    for by_rule in (True, False):
        group = [f for f in found if f.degree > 0 and f.by_rule == by_rule]
        if not group:
            continue
        degrees = sorted({f.degree for f in group})
        some = f"at {len(group)} of {len(found)} steps"
        where = "at every step" if len(group) == len(found) else some
        degree = f"{degrees[0]}" if len(degrees) == 1 else f"{degrees[0]} to {degrees[-1]}"
        sentences.append(split_words(over_steps(group, joints), where, degree))
    return " ".join(s for s in sentences if s) or None


def split_words(found: Indeterminacy, where: str = "", degree: str | None = None) -> str | None:
    """The forces' sentence of ``found`` (None where its degree is 0);
    ``where``: the steps it holds at, ``degree`` as said there."""
    if found.degree <= 0:
        return None
    names = list(found.joints)
    if not names:
        shared = "the touching contacts"
    elif len(names) == 1:
        shared = f"the contacts of {names[0]}"
    elif len(names) <= NAMED_JOINTS:
        shared = ", ".join(names[:-1]) + f" and {names[-1]}"
    else:
        shared = ", ".join(names[:NAMED_JOINTS]) + f" and {len(names) - NAMED_JOINTS} other joints"
    at = f"{where}, " if where else ""
    degree = str(found.degree) if degree is None else degree
    if not found.by_rule:
        return (
            f"Forces: {at}the load shared by {shared} is split as the solver left it (statically "
            f"indeterminate, degree {degree}), not by the equal-springs rule: other splits "
            "balance the loads as well; the rigid parts do not decide it; give `stiffness` "
            "for the real split."
        )
    return (
        f"Forces: {at}the load shared by {shared} is split by the equal-springs rule "
        f"(statically indeterminate, degree {degree}); the rigid parts do not decide it; "
        "give `stiffness` for the real split."
    )


def certificate_words(result: Result) -> str:
    """The certificate's line: what it proves, not the round-off it measured
    (the text and the report alike)."""
    cert, res = result.certificate, result.resolution
    springs = any(c.penetration > 0 for j in result.joints.values() for c in j.contacts)
    if cert.certified:
        return (
            f"certificate: holds ({cert.method}): no contact past its "
            f"{'reach (its play, and its spring under its force)' if springs else 'play'} by "
            f"{res.length:.2g} mm or more; the loads and contact forces of every body "
            f"balance to {res.balance:.2g} N "
            f"({result.equilibrium_tolerance:g} of the largest force)"
        )
    return (
        f"certificate: FAILED ({cert.method}): past clearance {cert.feasibility_mm:.1e} "
        f"mm, imbalance {result.equilibrium_residual:.1e} of the largest force"
    )


def render(
    model: Model, result: Result, source: str, console: Console, case: str | None = None
) -> None:
    title = model.name or source
    header = Text()
    header.append(f"{title}" + (f" - load case '{case}'" if case else "") + "\n", style="bold")
    if model.measured:
        given = "; ".join(m.describe() for m in model.measured)
        header.append(f"measured deviations: {given}\n")
    header.append(f"status: {result.status}\n")
    header.append(certificate_words(result) + "\n")
    energy = result.potential_energy + 0.0  # no "-0" when nothing moves
    header.append(f"potential energy of the loads: {energy:.9g} N*mm\n")
    header.append(
        f"linearization error (contacts placed with exact rotations, past their play): "
        f"{result.linearization_error:.3g} mm"
    )
    for warning in result.warnings:
        header.append(f"\nwarning: {warning}", style="bold yellow")
    parts: list[Table | Text] = [header]
    header.append(f"\ncontact forces are those of {'a on b'} for each joint 'between: [a, b]'")
    split = indeterminacy_words(result)
    if split is not None:
        header.append(f"\n{split}")

    for joint in model.joints:
        jr = result.joints[joint.name]
        a, b = jr.between
        table = Table(
            title=(f"joint {jr.name} ({jr.type}) at {fmt_point(jr.centre)}: {b} relative to {a}"),
            title_justify="left",
            show_edge=False,
        )
        table.add_column("axis")
        table.add_column("direction (global)")
        table.add_column("translation (mm)", justify="right")
        table.add_column("rotation (rad)", justify="right")
        for i, axis in enumerate("xyz"):
            direction = "[" + ", ".join(f"{c:.4g}" for c in jr.R_world_joint[:, i] + 0.0) + "]"
            table.add_row(axis, direction, _num(jr.translation[i]), _num(jr.rotation[i]))
        contacts = ", ".join(
            f"{c.name}: {'TOUCHING' if c.in_contact else 'free'} ({100 * c.gap_used:.2f}% of play"
            + (f", {c.penetration:.6g} {c.unit} past it)" if c.penetration > 0 else ")")
            for c in jr.contacts
        )
        parts.append(table)
        parts.append(Text(f"  contacts: {contacts}"))
        forces = Table(show_edge=False, box=None, padding=(0, 1))
        forces.add_column("  force (N)")
        forces.add_column("|F|", justify="right")
        forces.add_column("F (joint frame)")
        forces.add_column("at (global) or moment")
        for c in jr.contacts:
            if c.in_contact and np.any(c.torque) and not np.any(c.force):  # a drive's torque
                forces.add_row(f"  {c.name}", "", "", f"{_vec(c.torque, 6)} N*mm")
            elif c.in_contact:
                forces.add_row(
                    f"  {c.name}", f"{c.force_magnitude:.6g}", _vec(c.force, 6), fmt_point(c.point)
                )
        forces.add_row(
            "  reaction",
            f"{float(np.linalg.norm(jr.reaction_force)):.6g}",
            _vec(jr.reaction_force, 6),
            f"{_vec(jr.reaction_moment, 6)} N*mm",
        )
        parts.append(forces)

    exact = any(br.R is not None for br in result.bodies.values())
    body_table = _xyz_table(
        "bodies: "
        + ("exact placement (rotation vector)" if exact else "small displacement")
        + " at the global origin, in global axes",
        ["body", ""],
    )
    for name, br in result.bodies.items():
        if model.body(name).ground:
            continue
        body_table.add_row(name, "translation (mm)", *(_num(v, 6) for v in br.translation))
        body_table.add_row("", "rotation (rad)", *(_num(v, 6) for v in br.rotation))
    parts.append(body_table)
    if result.points:
        point_table = _xyz_table(
            "functional points: displacement in global axes (mm)", ["point", "body"]
        )
        point_table.add_column("|u|", justify="right")
        for pr in result.points.values():
            d = pr.displacement
            point_table.add_row(
                pr.name, pr.body, *(_num(v, 6) for v in d), _num(float(np.linalg.norm(d)), 6)
            )
        parts.append(point_table)
    checks = result.requirements
    if checks:
        req_table = Table(
            title="requirements on this solution (mm)", title_justify="left", show_edge=False
        )
        for name in ("point", "bounds", "measured", "limit", "margin", "verdict"):
            req_table.add_column(name, justify="left" if name in ("point", "bounds") else "right")
        for check in checks:
            req = check.requirement
            req_table.add_row(
                req.point,
                "|d|" if req.along is None else f"|d . {_vec(np.asarray(req.along), 3)}|",
                f"{check.measured:.6g}",
                f"{req.max_displacement:g}",
                f"{check.margin:.6g}",
                "pass" if check.passed else "FAIL",
                style=None if check.passed else "bold red",
            )
        parts.append(req_table)
    if result.free_motions:
        parts.append(
            Text(
                "free motions that no joint holds and no load drives (reported as 0):\n"
                + "\n".join(f"  {m}" for m in result.free_motions)
            )
        )
    console.print(_fit(console, *parts))


def render_montecarlo(result: MonteCarloResult, source: str, console: Console) -> None:
    """The report of ``jointplay montecarlo``: plays, points, requirements."""
    mc = result.settings
    head = Text()
    head.append(f"{result.model_name or source}: Monte Carlo\n", style="bold")
    head.append(
        f"{result.samples:,} sets of parts, seed {mc.seed}"
        + (f", load case '{mc.case}'" if mc.case else "")
        + f"; every sample certified ({result.batched:,} by batched Newton, "
        f"{result.full_solves:,} full solve{'' if result.full_solves == 1 else 's'}): "
        f"{CERTIFIED}\n"
    )
    if result.unassembled:
        head.append(
            f"{result.unassembled:,} sets of parts cannot be assembled: their deviations leave "
            "no position inside every clearance; they are left out of the points' figures "
            "and count as missing every requirement\n",
            style="bold",
        )
    drawn = "plays, loads and deviations" if result.deviations_described else "plays and loads"
    plays = Table(title=f"{drawn} drawn", title_justify="left", show_edge=False)
    plays.add_column("variable")
    plays.add_column("limits and law")
    described = result.plays_described | result.loads_described | result.deviations_described
    for label, words in described.items():
        plays.add_row(label, words)
    points = Table(
        title="functional points: size of the displacement (mm)",
        title_justify="left",
        show_edge=False,
    )
    for name in ("point", "mean", "std", "0.135 %", "median", "99.865 %", "max"):
        points.add_column(name, justify="left" if name == "point" else "right")
    for name, ps in result.points.items():
        pct = ps.size_percentiles
        points.add_row(
            name,
            *(
                f"{v:.6g}"
                for v in (
                    ps.size_mean,
                    ps.size_std,
                    pct[0.135],
                    pct[50.0],
                    pct[99.865],
                    ps.size_max,
                )
            ),
        )
    parts: list[Table | Text] = [head, plays, points]
    if result.requirements:
        reqs = Table(
            title=f"requirements: parts outside ({mc.confidence:.0%} interval)",
            title_justify="left",
            show_edge=False,
        )
        for name in ("requirement", "outside", "fraction", "ppm", "interval"):
            reqs.add_column(name, justify="left" if name == "requirement" else "right")
        for rs in result.requirements:
            lo, hi = rs.interval
            reqs.add_row(
                rs.requirement.describe(),
                f"{rs.outside:,}",
                f"{rs.fraction:.4%}",
                f"{rs.fraction * 1e6:.0f}",
                f"{lo:.3%} to {hi:.3%}",
            )
        parts.append(reqs)
    if mc.target_rel_error is not None:
        worst = float(np.max(result.relative_error, initial=0.0))
        met = "reached" if worst <= mc.target_rel_error else "NOT reached (raise --samples)"
        parts.append(
            Text(
                f"target relative error {mc.target_rel_error:g} at {mc.confidence:.0%}: {met}; "
                f"worst estimate's relative error {worst:.3g}"
            )
        )
    console.print(_fit(console, *parts))


def render_envelope(
    result: EnvelopeResult, source: str, title: str | None, console: Console
) -> None:
    """The report of ``jointplay envelope``."""
    st = result.settings
    head = Text()
    head.append(f"{title or source}: worst-case envelope of point '{st.point}'\n", style="bold")
    head.append(
        f"every displacement the plays allow under {result.over or 'any load'} (plays at "
        f"their {'upper limits' if st.plays == 'max' else 'means'}, stiffness left out)\n"
    )
    for words in result.not_held:
        head.append(f"not held, left out: {words}\n")
    size = result.largest
    direction = result.largest_direction
    head.append(f"largest displacement: {size:.6g} mm along {_vec(direction)}\n")
    table = Table(title="extent along each axis (mm)", title_justify="left", show_edge=False)
    for name in ("axis", "least", "greatest"):
        table.add_column(name, justify="left" if name == "axis" else "right")
    for i, axis in enumerate("XYZ"):
        lo, hi = result.extent[i]
        table.add_row(axis, f"{lo + 0.0:.6g}", f"{hi + 0.0:.6g}")
    console.print(_fit(console, head, table))


#: Rows of a sweep printed to the terminal; the rest go to --csv.
SWEEP_ROWS = 40


def _largest_step(sizes: FloatArray) -> int:
    """The step of the largest size (ties: the first)."""
    top = float(np.max(sizes))
    return int(np.flatnonzero(sizes >= top * (1 - 1e-12))[0])


def render_sweep(
    result: SweepResult, source: str, console: Console, csv: Path | None = None
) -> None:
    """The report of ``jointplay sweep``: a row per step, then each point's worst step."""
    head = Text()
    head.append(f"{result.model_name or source}: sweep of {result.steps} steps\n", style="bold")
    head.append("parameters: " + ", ".join(result.labels) + "\n")
    head.append(f"every step certified: {CERTIFIED}")
    table = Table(show_edge=False)
    table.add_column("step", justify="right")
    for label in result.labels:
        table.add_column(label, justify="right")
    for name in result.point_names:
        table.add_column(f"|d {name}| (mm)", justify="right")
    table.add_column("touching")
    sizes = np.linalg.norm(result.points, axis=2)  # (S, P)
    every = -(-result.steps // SWEEP_ROWS) if result.steps > SWEEP_ROWS else 1
    # each point's largest step too, which the summary below names
    worst = [_largest_step(sizes[:, p]) for p in range(sizes.shape[1])]
    shown_rows = sorted({*range(0, result.steps, every), *worst})
    for s in shown_rows:
        touching = [
            f"{j}.{c}" for k, (j, c) in enumerate(result.contact_names) if result.in_contact[s, k]
        ]
        table.add_row(
            str(s),
            *(f"{v:.6g}" for v in result.values[s]),
            *(f"{d:.6g}" for d in sizes[s]),
            ", ".join(touching) or "-",
        )
    parts: list[Table | Text] = [head, table]
    tail = Text()
    if len(shown_rows) < result.steps:
        where = f"written to {csv}" if csv else "--csv FILE writes them"
        tail.append(
            f"(one step in {every} of {result.steps} shown, and each point's largest; "
            f"all {where})\n"
        )
    for p, name in enumerate(result.point_names):
        s = worst[p]
        at = ", ".join(
            f"{label} = {v:.6g}" for label, v in zip(result.labels, result.values[s], strict=True)
        )
        tail.append(
            f"point {name}: largest displacement {sizes[s, p]:.6g} mm at step {s} ({at}), "
            f"along {_vec(result.points[s, p] / max(sizes[s, p], 1e-300))}\n"
        )
    split = steps_split_words(result.indeterminate, result.joint_names)
    if split is not None:
        tail.append(split + "\n")
    if tail:
        parts.append(tail)
    console.print(_fit(console, *parts))


def render_motion(
    result: Any,
    source: str,
    console: Console,
    columns: Mapping[str, Sequence[float] | Sequence[str]] | None = None,
    findings: Sequence[str] = (),
) -> None:
    """The report of ``jointplay motion``: one line per step, then each
    requirement's worst step. ``columns``: more cells per step (the studies
    over the motion: numbers in mm, or names); ``findings``: their sentences."""
    head = Text()
    head.append(
        f"{result.model_name or source}: motion of {result.steps} steps, drive "
        f"'{result.drive}' ({result.coordinate})"
        + ("" if result.case is None else f", load case '{result.case}'")
        + "\n",
        style="bold",
    )
    head.append(f"every step certified: {CERTIFIED}")
    table = Table(show_edge=False)
    table.add_column("step", justify="right")
    table.add_column(f"drive ({result.unit})", justify="right")
    for name in result.point_names:
        table.add_column(f"{name} at (mm)", justify="right")
        table.add_column(f"d {name} (mm)", justify="right")
    table.add_column(f"drive reaction ({result.reaction_unit})", justify="right")
    table.add_column("touching")
    extra = dict(columns or {})
    for header in extra:
        table.add_column(header, justify="right")
    for s in range(result.steps):
        cells = [str(s), f"{result.shown_value(s):.6g}"]
        for k in range(len(result.point_names)):
            cells += [_vec(result.nominal[s, k], 6), _vec(result.displacement[s, k], 4)]
        cells += [
            f"{result.drive_reaction[s]:.6g}",
            _touching_by_joint(result.results[s], result.switched[s]),
        ]
        cells += [
            value if isinstance(value, str) else f"{value:.4g}"
            for value in (values[s] for values in extra.values())
        ]
        table.add_row(*cells)
    tail = Text()
    if any(result.switched):
        tail.append(f"{SWITCHED}: {SWITCHED_LEGEND}\n")
    for q, name in enumerate(result.requirement_names):
        s = result.worst_step(q)
        failing = int(np.sum(result.measured[:, q] > result.limits[q]))
        tail.append(
            f"requirement on {name}: passed at every step"
            if not failing
            else f"requirement on {name}: FAILED at {failing} of {result.steps} steps"
        )
        tail.append(
            f"; worst at step {s} (drive {result.shown_value(s):.6g} {result.unit}): "
            f"{result.measured[s, q]:.6g} mm of {result.limits[q]:g} mm\n"
        )
    split = steps_split_words(result.indeterminate, result.joint_names)
    if split is not None:
        tail.append(split + "\n")
    for sentence in findings:
        tail.append(sentence + "\n")
    console.print(_fit(console, head, table, tail))


#: Marks a contact in the motion's table that switched at that step.
SWITCHED = "*"
SWITCHED_LEGEND = (
    "a contact that switches at that step: it starts touching, stops ('off'), or pushes the "
    "other way (the play crossed: an impact in a running machine)"
)


def _touching_by_joint(result: Any, switched: Mapping[str, Sequence[str]] | None = None) -> str:
    """The touching contacts, grouped by joint: 'pin (end-, end+), guide (x-)';
    those in ``switched`` (per joint) marked, one that stopped touching as 'x+ off*'."""
    groups = []
    for name, joint in result.joints.items():
        marked = set((switched or {}).get(name, ()))
        shown = [
            c.name + (SWITCHED if c.name in marked else "")
            if c.in_contact
            else f"{c.name} off{SWITCHED}"
            for c in joint.contacts
            if c.in_contact or c.name in marked
        ]
        if shown:
            groups.append(f"{name} ({', '.join(shown)})")
    return ", ".join(groups) or "-"


def _bar(percent: float, width: int = 10) -> str:
    full = round(width * percent / 100.0)
    return "#" * full + "." * (width - full)


def render_contributions(result: ContributionsResult, source: str, console: Console) -> None:
    """The report of ``jointplay contributions``: per measure, a row per play."""
    head = Text()
    head.append(f"{result.model_name or source}: contributions\n", style="bold")
    for play, words in result.plays_described.items():
        head.append(f"  {play}: {words}\n")
    if any(result.linear(k) for k in range(len(result.measures))):  # the linear columns
        head.append(
            "sensitivity s: mm of the measure per mm of play (per rad of a backlash, per N or "
            "N*mm of a load; for a deviation zone the size of the gradient, per mm or rad "
            "in its worst direction, T its diameter), at "
            "the nominal (mean) values; worst case: |s| T of the stack sum |s| T, T the "
            "tolerance; RSS: (s sigma)^2 of sum (s sigma)^2"
        )
    parts: list[Table | Text] = [head]
    rss = result.rss
    for k, measure in enumerate(result.measures):
        # the figures above the table, not as its title: a title is cut to the
        # table's width, numbers and all
        spread = (
            f"worst-case spread {result.worst_case_range[k]:.6g} mm, RSS sigma "
            f"{result.rss_sigma[k]:.6g} mm"
            if result.linear(k)
            else "the linear stack and RSS do not hold over the ranges"
        )
        parts.append(Text(f"{measure}: {result.nominal[k]:.6g} mm at the nominal; {spread}"))
        order = np.argsort(-rss[k], kind="stable")
        # the widest that fits: with bars, then without, then names folded
        wide = console.options.update_width(10_000)
        by_variance = not result.linear(k) and result.sobol is not None
        if by_variance:
            parts.append(_not_linear_words(result, k))
            order = np.argsort(-result.sobol.total[k], kind="stable")  # type: ignore[union-attr]
        for bars, whole_names in ((True, True), (False, True), (False, False)):
            table = (
                _variance_table(result, k, order, bars, whole_names)
                if by_variance
                else _contributions_table(result, k, order, bars, whole_names)
            )
            if console.measure(table, options=wide).maximum <= console.width:
                break
        notes = Text()
        for i in order:
            if result.kink[k, i]:
                notes.append(
                    f"  {result.plays[i]}: the contacts change at its nominal value; the slope is "
                    f"{result.slope_down[k, i]:.6g} below it and {result.slope_up[k, i]:.6g} "
                    "above" + ("" if by_variance else " (the mean of the two is used)") + "\n"
                )
        parts.append(table)
        if notes:
            parts.append(notes)
        if result.sobol is not None and not by_variance:  # asked for, or for another measure
            if not result.sobol.variance[k] > 0:  # its indices are NaN: no table of them
                parts.append(
                    Text("the shares of its variance (Sobol' indices): none, it does not vary")
                )
                continue
            parts.append(Text("the shares of its variance (Sobol' indices):"))
            by_total = np.argsort(-result.sobol.total[k], kind="stable")
            parts.append(_variance_table(result, k, by_total, False, True))
    console.print(_fit(console, *parts))


def _contributions_table(
    result: ContributionsResult, k: int, order: Any, bars: bool, whole_names: bool
) -> Table:
    """Measure ``k``'s rows in ``order``; ``bars``: with the RSS share drawn;
    ``whole_names``: the variables' names on one line."""
    wc, rss = result.worst_case, result.rss
    table = Table(show_edge=False)
    widest = max((len(p) for p in result.plays), default=8)
    names = ("variable", "tolerance T", "sensitivity s", "worst case", "RSS", "")
    for name in names[: len(names) if bars else -1]:
        table.add_column(
            name,
            justify="left" if name in ("variable", "") else "right",
            min_width=widest if name == "variable" and whole_names else None,
        )
    for i in order:
        row = [
            result.plays[i],
            f"{result.width[i]:.6g}",
            f"{result.sensitivity[k, i]:.6g}",
            f"{wc[k, i]:5.1f} %",
            f"{rss[k, i]:5.1f} %",
        ]
        table.add_row(*row, *([_bar(rss[k, i])] if bars else []))
    return table


def render_tolerances(result: TolerancesResult, source: str, console: Console) -> None:
    """The report of ``jointplay tolerances``: per requirement, the worst case
    (the greatest over the tolerances' limits, and the linear estimate where it agrees),
    RSS where the measure is linear, and Monte Carlo, side by side (mm; ppm
    out of the limits)."""
    mc = result.montecarlo
    head = Text()
    head.append(f"{result.model_name or source}: tolerance results side by side\n", style="bold")
    for play, words in result.linear.plays_described.items():
        head.append(f"  {play}: {words}\n")
    head.append(
        "worst case: the measure's greatest value (along a direction, the least and the "
        "greatest d . u) over every combination of the tolerances' "
        "limits (each a certified equilibrium; with deviation zones, over every position they "
        "allow), passed only if no Monte Carlo sample goes past it, with the linear stack "
        "y0 -/+ sum |s| T / 2 as an estimate where it "
        "agrees; RSS: sigma = sqrt(sum (s sigma)^2), normal law, only where the measure is "
        f"linear over the ranges; Monte Carlo: {mc.samples:,} sets of parts (seed "
        f"{result.settings.seed}), ppm with its {result.settings.confidence:.0%} interval. "
        "Cp/Pp only for a two-sided requirement (a component along a direction); "
        "docs/tolerancing.md says which holds when"
    )
    if mc.unassembled:
        head.append(
            f"\n{mc.unassembled:,} of the sets of parts cannot be assembled (their deviations "
            "leave no position inside every clearance): Monte Carlo counts them out of "
            "every limit and leaves them out of its mean and sigma",
            style="bold",
        )
    parts: list[Table | Text] = [head]
    for r in result.requirements:
        parts.extend(_tolerance_table(r, mc.samples))
    console.print(_fit(console, *parts))


def _cap(value: float) -> str:
    return "-" if value != value else f"{value:.3g}"  # NaN: not defined (one-sided)


#: What the RSS column says where the measure is not linear over the ranges.
NOT_APPLICABLE = "n/a"


def _tolerance_table(r: Any, samples: int) -> list[Table | Text]:
    """One requirement's (``RequirementTolerances``) side-by-side table, and the
    notes under it: where the worst case is reached, why RSS does not apply."""
    low, high = r.limits
    span = f"{low:g} to {high:g}" if low is not None else f"at most {high:g}"
    note = " (contacts change at the nominal)" if r.kink else ""
    table = Table(
        title=f"{r.requirement.describe()}; nominal {r.nominal:.6g} mm{note}",
        title_justify="left",
        show_edge=False,
    )
    for name in ("", "worst case", "RSS", "Monte Carlo"):
        table.add_column(name, justify="left" if not name else "right")
    verdict = "pass" if r.worst_case_passes else "FAIL"
    # along a direction, the signed range reached: one sign where the point goes one way
    if r.two_sided and r.worst_low is not None and r.worst_high is not None:
        bound = f"{r.worst_low + 0.0:.5g} to {r.worst_high + 0.0:.5g}"
    else:
        bound = f"up to {r.worst:.5g}"
    na = NOT_APPLICABLE
    rss = r.rss_applies

    def when(text: str) -> str:
        return text if rss else na

    table.add_row("mm", bound, "", f"{r.mc_low:.5g} to {r.mc_high:.5g}")
    estimate = f"{r.linear_low:.5g} to {r.linear_high:.5g}" if r.linear_agrees else na
    table.add_row("linear estimate", estimate, "", "")
    table.add_row("mean (mm)", "", when(f"{r.nominal:.6g}"), f"{r.mc_mean:.6g}")
    table.add_row("sigma (mm)", "", when(f"{r.rss_sigma:.4g}"), f"{r.mc_sigma:.4g}")
    table.add_row("Cp, Pp", "", when(_cap(r.cp)), _cap(r.pp))
    table.add_row("Cpk, Ppk", "", when(_cap(r.cpk)), _cap(r.ppk))
    lo, hi = r.mc_interval_ppm
    table.add_row("ppm out", verdict, when(f"{r.rss_ppm:.4g}"), f"{r.mc_ppm:.4g}")
    table.add_row("", f"(limits {span})", "(normal law)" if rss else "", f"[{lo:.4g}, {hi:.4g}]")
    notes = Text()
    where = f" (d . u = {r.worst_signed:.5g} mm)" if r.worst_signed is not None else ""
    notes.append(
        f"worst case {r.worst:.6g} mm{where}, at {r.worst_at}: the greatest over {r.worst_over}\n"
    )
    if not r.linear_agrees:
        notes.append(
            f"linear estimate {r.linear_low:.5g} to {r.linear_high:.5g} mm: not shown, it "
            "does not agree with the worst case (the slopes at the nominal do not hold "
            "over the ranges)\n"
        )
    if not rss:
        notes.append(
            f"RSS, Cp, Cpk: not applicable: {r.linear_why}; the verdict comes from the worst "
            "case and the Monte Carlo\n"
        )
    if r.beyond_words(samples):
        notes.append(r.beyond_words(samples) + "\n", style="bold")
    return [table, notes]


def _not_linear_words(result: ContributionsResult, k: int) -> Text:
    """Why measure ``k``'s linear shares do not hold, and what replaces them."""
    sobol = result.sobol
    assert sobol is not None
    return Text(
        f"  not linear over the ranges: {result.linearity[k].why()}. So the shares below are "
        f"of the variance, Sobol' indices from {sobol.settings.samples:,} base sets of parts "
        f"({sobol.solves:,} solves, {sobol.settings.confidence:.0%} intervals): first order, "
        "what an input explains alone; total, with its interactions (total - first: its "
        "share in interactions, contacts that change with several inputs together)"
    )


def _variance_table(
    result: ContributionsResult, k: int, order: Any, bars: bool, whole_names: bool
) -> Table:
    """Measure ``k``'s rows by their shares of the variance (Sobol'), in ``order``."""
    sobol = result.sobol
    assert sobol is not None
    table = Table(show_edge=False)
    widest = max((len(p) for p in result.plays), default=8)
    names = ("variable", "tolerance T", "first order %", "total %", "interactions %", "")
    for name in names[: len(names) if bars else -1]:
        table.add_column(
            name,
            justify="left" if name in ("variable", "") else "right",
            min_width=widest if name == "variable" and whole_names else None,
        )

    for i in order:
        total = float(sobol.total[k, i])
        row = [
            result.plays[i],
            f"{result.width[i]:.6g}",
            sobol_share(float(sobol.first[k, i]), sobol.first_interval[k, i]),
            sobol_share(total, sobol.total_interval[k, i]),
            percent(float(sobol.interactions[k, i])),
        ]
        table.add_row(*row, *([_bar(min(max(100 * total, 0.0), 100.0))] if bars else []))
    return table
