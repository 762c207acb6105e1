"""The ``jointplay`` command line. Exit codes: 0 solved, 2 invalid model,
3 mechanism not held by its joints, 4 a requirement fails (only with
``--fail-on-requirements``), 1 anything else."""

from __future__ import annotations

import dataclasses
import json
import os
import shlex
import sys
import traceback
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any, Literal, TypeVar

import typer
from rich.console import Console

from jointplay import __version__
from jointplay.errors import (
    JointplayError,
    OptionError,
    StudyError,
    UnassembledError,
    UnboundedMechanismError,
)
from jointplay.settings import MOST_MOTION_STEPS
from jointplay.units import LIMITS

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="Where the parts of a mechanism really sit when its joints have clearance.",
    pretty_exceptions_enable=False,
    # help texts are plain text: "joints[l2]" is a path, not Rich markup
    rich_markup_mode=None,
)

#: ``solve --fail-on-requirements``: solved and certified, but a requirement fails
#: (``motion --fail-on-requirements``: at a step of the nominal motion).
REQUIREMENT_FAILED = 4

R = TypeVar("R")

ModelPath = Annotated[
    Path, typer.Argument(metavar="MODEL", help="Model file (.yaml, .json, .toml).")
]
CaseOption = Annotated[
    str | None, typer.Option("--case", metavar="NAME", help="Load case to solve.")
]
SchedulerOption = Annotated[
    str | None,
    typer.Option(
        "--scheduler", metavar="ADDRESS", help="Solve on a Dask cluster (tcp://host:8786)."
    ),
]


WorkersOption = Annotated[
    int | None,
    typer.Option("--workers", min=1, help="Local processes (default: one per core)."),
]
PlotOption = Annotated[
    Path | None,
    typer.Option("--plot", metavar="FILE", help="Draw the study's figure (.png, .svg or .pdf)."),
]


VaryOption = Annotated[
    list[str] | None,
    typer.Option(
        "--vary",
        metavar="PATH=START:STOP:COUNT",
        help="Vary an entry of the model, named by its path in the file: "
        "'loads[0].force[1]=0:10:11', 'joints[l2].clearance=0.1:0.3:5' (a bracket may "
        "hold a name), values with units ('0:10 N:11') or a list 'PATH=1,2,5'. "
        "Repeat for a grid.",
    ),
]
RotateLoadOption = Annotated[
    int | None,
    typer.Option(
        "--rotate-load",
        metavar="N",
        min=0,
        help="Turn load N (counted from 0 in 'loads') about --about: its force and torque "
        "turn, its point stays.",
    ),
]
AboutOption = Annotated[
    str, typer.Option("--about", metavar="AXIS", help="x, y, z, or 'ax,ay,az'.")
]
StepsOption = Annotated[
    int, typer.Option("--steps", min=1, help="Steps of the turn (a full turn by default).")
]
FromOption = Annotated[
    float, typer.Option("--from", metavar="DEG", help="First angle of the turn.")
]
ToOption = Annotated[
    float | None,
    typer.Option("--to", metavar="DEG", help="Last angle (taken); default: a full turn."),
]


def _json(doc: Any) -> str:
    """``doc`` as JSON that every parser reads: a number that is not finite
    (an estimate's relative error with no failing part) is written null,
    since JSON has no Infinity or NaN."""

    def finite(v: Any) -> Any:
        if isinstance(v, float):
            return v if v == v and abs(v) != float("inf") else None
        if isinstance(v, dict):
            return {k: finite(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [finite(x) for x in v]
        return v

    return json.dumps(finite(doc), indent=2, allow_nan=False)


def _sweep_settings(
    vary: list[str] | None,
    rotate_load: int | None,
    about: str,
    steps: int,
    start_deg: float,
    stop_deg: float | None,
    case: str | None,
    chunk: int,
    source: str,
) -> Any:
    """The ``Sweep`` that the sweep options describe (a ``ModelError`` if they are wrong)."""
    from jointplay.studies.sweep import RotateLoad, Sweep, Vary

    try:
        varies = tuple(Vary.parse(v) for v in vary or ())
        turn = (
            None
            if rotate_load is None
            else RotateLoad(rotate_load, RotateLoad.axis(about), steps, start_deg, stop_deg)
        )
        return Sweep(varies, turn, case, chunk)
    except ValueError as exc:
        raise OptionError(str(exc), source=source) from None


def _measured(options: list[str], source: str) -> dict[str, dict[str, Any]]:
    """``--deviations`` options as ``{joint: {kind: [x, y, z]}}``."""
    import yaml

    out: dict[str, dict[str, Any]] = {}
    for option in options:
        name, eq, text = option.partition("=")
        joint, dot, kind = name.strip().rpartition(".")
        try:
            value = yaml.safe_load(text) if eq else None
        except yaml.YAMLError:
            value = None
        if not (eq and dot and joint) or not isinstance(value, list):
            raise OptionError(
                f"--deviations {option!r}: write JOINT.position=[x, y, z] or "
                "JOINT.orientation=[0, wy, wz], e.g. 'l2.position=[0, 5 um, -3 um]'",
                source=source,
            )
        if kind in out.get(joint, {}):
            raise OptionError(
                f"--deviations {option!r}: {joint}.{kind} is given twice; give it once",
                source=source,
            )
        out.setdefault(joint, {})[kind] = value
    return out


def _version(value: bool) -> None:
    if value:
        typer.echo(f"jointplay {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Show the version.")
    ] = False,
) -> None:
    """Clearance equilibrium of mechanisms: positions, contacts, certificates."""


@app.command(short_help="Where the parts sit: positions, contacts, forces, certificate.")
def solve(
    model_path: ModelPath,
    as_json: Annotated[bool, typer.Option("--json", help="Print the result as JSON.")] = False,
    case: Annotated[
        str | None,
        typer.Option("--case", metavar="NAME", help="Solve only this load case of the model."),
    ] = None,
    exact: Annotated[
        bool,
        typer.Option(
            "--exact",
            help="Refine with exact rotations (re-linearized until the exact geometry "
            "holds within 1e-9 mm).",
        ),
    ] = False,
    fail_on_requirements: Annotated[
        bool,
        typer.Option(
            "--fail-on-requirements",
            help=f"Exit with code {REQUIREMENT_FAILED} when a requirement fails for the "
            "solution of any load case (after printing everything): a gate for CI.",
        ),
    ] = False,
    deviations: Annotated[
        list[str] | None,
        typer.Option(
            "--deviations",
            metavar="JOINT.KIND=[..]",
            help="A joint's (or a shared) deviation as measured on a part, in its frame: "
            "'l2.position=[0, 5 um, -3 um]' or 'l2.orientation=[0, 0.1 mrad, 0]' "
            "(repeat for more). Without it every deviation is at its mean.",
        ),
    ] = None,
) -> None:
    """Solve the equilibrium of MODEL: joints, contacts, forces and bodies, and
    each requirement's pass or fail.

    A model with load cases is solved for each case (or only --case NAME).
    """
    from jointplay.io.modelfile import load
    from jointplay.model.deviations import measured_doc
    from jointplay.present.textreport import render
    from jointplay.solver.solve import Workspace

    failed = False
    not_held: dict[str, UnboundedMechanismError] = {}  # load case -> its verdict

    def run() -> None:
        nonlocal failed
        from jointplay.model.mechanism import check_case

        model = load(model_path)
        if deviations:
            from jointplay.io.modelfile import with_deviations

            measured = _measured(deviations, str(model_path))
            model = with_deviations(model, measured, source=str(model_path))
        check_case(model, case, str(model_path))
        ws = Workspace.of(model)
        if model.case_names:
            names: list[str | None] = [case] if case is not None else list(model.case_names)
        else:
            names = [None]
        results = {}
        for name in names:
            try:
                loads = None if name is None else model.loads_of(name)
                results[name] = ws.solve(loads=loads, exact=exact)
            except UnassembledError as exc:  # the model's own parts: name its file
                raise UnassembledError(
                    exc.problem, joints=exc.joints, source=str(model_path)
                ) from None
            except UnboundedMechanismError as exc:
                if name is None:
                    raise
                # the cases it holds are printed still; the verdict names its case
                not_held[name] = exc.in_case(name)
        failed = any(not r.passed for result in results.values() for r in result.requirements)
        if as_json:
            docs = {
                name: _error_doc(not_held[name]) if name in not_held else results[name].to_dict()
                for name in names
            }
            whole: dict[str, Any] = {"status": "optimal"}
            if not_held:  # the verdict's own keys, as without cases, and the case it is under
                first = next(iter(not_held))
                whole = {**_error_doc(not_held[first]), "case": first}
            doc = docs.get(None, {**whole, "cases": docs})
            if model.measured:  # the part solved, as given (mm, rad)
                doc["measured_deviations"] = measured_doc(model.measured)
            typer.echo(_json(doc))
        else:
            for name, result in results.items():
                render(model, result, str(model_path), _console(), case=name)
            _at_written_pose(model, str(model_path), as_json)

    _guarded(run, as_json)
    if not_held:
        for exc in not_held.values():
            _say(exc)
        raise typer.Exit(UnboundedMechanismError.exit_code)
    if failed and fail_on_requirements:
        raise typer.Exit(REQUIREMENT_FAILED)


@app.command(short_help="The model file's JSON Schema, for editors and checks.")
def schema() -> None:
    """Print the JSON Schema of the model file (draft 2020-12), generated from
    the validated model. Save it and point an editor at it: in a YAML file,
    the first line '# yaml-language-server: $schema=jointplay.schema.json'."""
    from jointplay.io.modelfile import json_schema

    typer.echo(json.dumps(json_schema(), indent=2))


@app.command(short_help="Monte Carlo over real parts drawn from their tolerances.")
def montecarlo(
    model_path: ModelPath,
    samples: Annotated[
        int,
        typer.Option(
            "--samples", "-n", min=1, help="Sets of parts to draw (the most, with --target)."
        ),
    ] = 10_000,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Random seed.")] = 0,
    target: Annotated[
        float | None,
        typer.Option(
            "--target",
            help="Stop when every estimate's relative error is below this (0.05 = 5 %): the "
            "fraction missing each requirement, else each point's mean displacement.",
        ),
    ] = None,
    confidence: Annotated[
        float,
        typer.Option(
            "--confidence",
            help="Confidence level of --target and of the intervals.",
        ),
    ] = 0.95,
    case: CaseOption = None,
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    chunk: Annotated[
        int, typer.Option("--chunk", min=1, help="Samples per chunk (fixes the random streams).")
    ] = 10_000,
    csv: Annotated[
        Path | None,
        typer.Option("--csv", metavar="FILE", help="Write every sample (plays, displacements)."),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the summary as JSON.")] = False,
    plot: PlotOption = None,
) -> None:
    """Monte Carlo over real parts: draw every toleranced play (limits or ISO
    fits), solve each set of parts exactly, and summarize the functional points
    and the requirements of MODEL."""
    from jointplay.io.modelfile import load
    from jointplay.present.textreport import render_montecarlo
    from jointplay.studies.montecarlo import MonteCarlo

    def run() -> None:
        model = load(model_path)
        for name, value in (("--target", target), ("--confidence", confidence)):
            if value is not None and not 0.0 < value < 1.0:
                raise OptionError(
                    f"{name} {value:g}: expected a fraction between 0 and 1 (0.05 is 5 %)",
                    source=str(model_path),
                )
        _check_outputs(csv, plot)
        study = MonteCarlo(samples, seed, target, confidence, chunk, case)
        result = _with_progress(
            "solving samples",
            samples,
            not as_json and samples > chunk,
            lambda progress: study.run(
                model,
                workers=workers,
                scheduler=scheduler,
                progress=progress,
                source=str(model_path),
            ),
        )
        _finish_study(
            result,
            csv,
            plot,
            lambda: _plots().montecarlo_figure(result),
            as_json,
            lambda: render_montecarlo(result, str(model_path), _console()),
        )
        _at_written_pose(model, str(model_path), as_json)

    _guarded(run, as_json)


@app.command(short_help="Worst-case envelope of a functional point under the loads it takes.")
def envelope(
    model_path: ModelPath,
    point: Annotated[
        str | None,
        typer.Option(
            "--point",
            metavar="NAME",
            help="The functional point to bound (without it: the model's only point, or "
            "its points are listed).",
        ),
    ] = None,
    directions: Annotated[
        int, typer.Option("--directions", min=6, help="Directions over the sphere.")
    ] = 200,
    plays: Annotated[
        str,
        typer.Option(
            "--plays",
            metavar="max|mean",
            help="Toleranced plays at their upper limits (every part inside) or means.",
        ),
    ] = "max",
    csv: Annotated[
        Path | None,
        typer.Option("--csv", metavar="FILE", help="Write each direction's support point."),
    ] = None,
    loads: Annotated[
        str,
        typer.Option(
            "--loads",
            metavar="auto|model|probes",
            help="Over the model's load cases and load ranges, or over probe forces at the "
            "point in every direction the mechanism holds (auto: the model's if it has cases "
            "or ranges).",
        ),
    ] = "auto",
    levels: Annotated[
        int | None,
        typer.Option(
            "--levels",
            min=2,
            help="Values of each varying load component (2: its limits; 3 adds its mean; "
            "default 3, or 2 where 3 would make over 100,000 load sets).",
        ),
    ] = None,
    probe: Annotated[
        float,
        typer.Option(
            "--probe", help="Probe force (N) against the weights and standing loads; > 0."
        ),
    ] = 1.0,
    case: Annotated[
        str | None,
        typer.Option("--case", metavar="NAME", help="Only this load case (default: every case)."),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the envelope as JSON.")] = False,
    plot: PlotOption = None,
) -> None:
    """Worst-case envelope of a functional point: every displacement the
    plays allow under the loads the mechanism takes (its largest size and
    direction, its extent along each axis, and the hull's points), and the
    probe directions it does not hold."""
    from jointplay.io.modelfile import load
    from jointplay.present.textreport import render_envelope
    from jointplay.settings import SMALLEST_PROBE
    from jointplay.studies.envelope import Envelope

    def run() -> None:
        if plays not in ("max", "mean"):
            raise OptionError(f"--plays {plays!r}: expected 'max' or 'mean'")
        if not SMALLEST_PROBE <= probe <= LIMITS["force"]:
            raise OptionError(
                f"--probe {probe:.10g}: expected a force of {SMALLEST_PROBE:g} to "
                f"{LIMITS['force']:g} N"
            )
        if loads not in ("auto", "model", "probes"):
            raise OptionError(f"--loads {loads!r}: expected 'auto', 'model' or 'probes'")
        _check_outputs(csv, plot)
        model = load(model_path)
        # the only point: nothing to choose
        bounded = model.points[0].name if point is None and len(model.points) == 1 else point
        if bounded is None:
            raise _no_point(model, model_path)
        settings = Envelope(
            bounded,
            directions,
            "max" if plays == "max" else "mean",
            "auto" if loads == "auto" else "model" if loads == "model" else "probes",
            levels,
            probe,
            case,
        )
        result = settings.run(model, source=str(model_path))
        _finish_study(
            result,
            csv,
            plot,
            lambda: _plots().envelope_figure(result),
            as_json,
            lambda: render_envelope(result, str(model_path), model.name, _console()),
        )

    _guarded(run, as_json)


@app.command(short_help="Solve as model entries vary or a load turns; a table per step.")
def sweep(
    model_path: ModelPath,
    vary: VaryOption = None,
    rotate_load: RotateLoadOption = None,
    about: AboutOption = "z",
    steps: StepsOption = 72,
    start_deg: FromOption = 0.0,
    stop_deg: ToOption = None,
    case: CaseOption = None,
    workers: Annotated[
        int | None,
        typer.Option(
            "--workers", min=1, help="Local processes (default: one per core above 1000 steps)."
        ),
    ] = None,
    scheduler: SchedulerOption = None,
    chunk: Annotated[int, typer.Option("--chunk", min=1, help="Steps per task.")] = 64,
    csv: Annotated[
        Path | None,
        typer.Option("--csv", metavar="FILE", help="Write the table (one row per step) as CSV."),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print every step as JSON.")] = False,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            metavar="FILE",
            help="Draw each point's trajectory inside its worst-case envelope, and the "
            "contact forces along the sweep (.png, .svg or .pdf).",
        ),
    ] = None,
) -> None:
    """Sweep MODEL: solve it as entries vary over a range or a load turns, and
    tabulate per step the points' displacements, the joints' torsors and the
    contacts (state and force)."""
    from jointplay.io.modelfile import load
    from jointplay.present.textreport import render_sweep

    def run() -> None:
        source = str(model_path)
        settings = _sweep_settings(
            vary, rotate_load, about, steps, start_deg, stop_deg, case, chunk, source
        )
        _check_outputs(csv, plot)
        model = load(model_path)
        n_workers = workers if workers is not None else (None if settings.steps >= 1000 else 1)
        result = _with_progress(
            "solving steps",
            settings.steps,
            not as_json and settings.steps >= 200,
            lambda progress: settings.run(
                model, workers=n_workers, scheduler=scheduler, progress=progress, source=source
            ),
        )
        _finish_study(
            result,
            csv,
            plot,
            lambda: _plots().sweep_figure(result, sweep_envelopes(model, source)),
            as_json,
            lambda: render_sweep(result, source, _console(), csv),
        )

    _guarded(run, as_json)


@app.command(short_help="The mechanism through its motion: the play's effect at every pose.")
def motion(
    model_path: ModelPath,
    drive: Annotated[
        str | None, typer.Option("--drive", metavar="JOINT", help="The joint that drives.")
    ] = None,
    span: Annotated[
        str | None,
        typer.Option(
            "--range", metavar="START:STOP", help="The drive's range, e.g. '0 deg:360 deg'."
        ),
    ] = None,
    steps: Annotated[
        int | None,
        typer.Option(
            "--steps",
            metavar="N",
            help=f"Steps, both ends included: 2 to {MOST_MOTION_STEPS:,} (each is a solve).",
        ),
    ] = None,
    case: Annotated[
        str | None,
        typer.Option(
            "--case",
            metavar="NAME",
            help="The load case the motion is under (needed when the model has load cases).",
        ),
    ] = None,
    csv: Annotated[
        Path | None,
        typer.Option("--csv", metavar="FILE", help="Write the table (one row per step) as CSV."),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print every step as JSON.")] = False,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            metavar="FILE",
            help="Draw each point's displacement against the drive and its path, and each "
            "joint's force with its contacts' switches, in one figure (.png, .svg or .pdf).",
        ),
    ] = None,
    samples: Annotated[
        int | None,
        typer.Option(
            "--samples",
            "-n",
            min=1,
            help="Monte Carlo: sets of parts, each carried through the whole motion.",
        ),
    ] = None,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Monte Carlo: random seed.")] = 0,
    workers: WorkersOption = None,
    envelope: Annotated[
        bool, typer.Option("--envelope", help="Each point's worst-case envelope at every pose.")
    ] = False,
    loads: Annotated[
        str | None,
        typer.Option(
            "--loads",
            metavar="auto|model|probes",
            help="With --envelope: over the model's loads at each pose, or over probe forces "
            "at the point in every direction the mechanism holds (auto: the model's if it has "
            "cases, ranges or tables over the drive).",
        ),
    ] = None,
    contributions: Annotated[
        bool,
        typer.Option("--contributions", help="Which play drives each measure, at every pose."),
    ] = False,
    variance: Annotated[
        str | None,
        typer.Option(
            "--variance",
            metavar="auto|always|never",
            help="With --contributions: the shares of the variance (Sobol' indices) at every "
            "pose: 'auto' where a measure is not linear over the ranges (the default), "
            "'always', or 'never' (the linear shares alone: much faster).",
        ),
    ] = None,
    sobol_samples: Annotated[
        int | None,
        typer.Option(
            "--sobol-samples",
            min=8,
            help="With --contributions: the Sobol' base sets of parts, a power of 2 (default "
            "1024; it solves samples x (inputs + 2) sets through the motion).",
        ),
    ] = None,
    fail_on_requirements: Annotated[
        bool,
        typer.Option(
            "--fail-on-requirements",
            help=f"Exit with code {REQUIREMENT_FAILED} when a requirement fails at any step "
            "of the nominal motion (after printing everything): a gate for CI. With "
            "--samples too, the nominal motion decides, not the Monte Carlo's parts.",
        ),
    ] = False,
) -> None:
    """Drive MODEL through its motion (its 'motion' section, or --drive and
    --range): every body's pose by its ideal joints, and at every pose the
    clearance equilibrium; a line per step. With --samples, a Monte Carlo over
    the motion (each set of parts through every pose); --envelope and
    --contributions add those studies at every pose."""
    from jointplay.io.modelfile import load
    from jointplay.present.textreport import render_motion
    from jointplay.studies.motion import Motion
    from jointplay.studies.motion_studies import (
        MotionContributions,
        MotionEnvelope,
        MotionMonteCarlo,
        MotionStudiesResult,
    )

    failed = False

    def run() -> None:
        nonlocal failed
        source = str(model_path)
        bounds = None
        if span is not None:
            parts = span.split(":")
            if len(parts) != 2:
                raise OptionError(
                    f"--range {span}: expected START:STOP, e.g. '0 deg:360 deg'", source=source
                )
            bounds = (parts[0].strip(), parts[1].strip())  # as written: "90" has no unit
        if loads is not None and loads not in ("auto", "model", "probes"):
            raise OptionError(
                f"--loads {loads!r}: expected 'auto', 'model' or 'probes'", source=source
            )
        if loads is not None and not envelope:  # it would be ignored: say so
            raise OptionError(
                f"--loads {loads}: the loads of the envelope at every pose; add --envelope",
                source=source,
            )
        if variance is not None and variance not in ("auto", "always", "never"):
            raise OptionError(
                f"--variance {variance!r}: expected 'auto', 'always' or 'never'", source=source
            )
        for name, given in (("--variance", variance), ("--sobol-samples", sobol_samples)):
            if given is not None and not contributions:  # it would be ignored: say so
                raise OptionError(
                    f"{name} {given}: a setting of the contributions at every pose; add "
                    "--contributions",
                    source=source,
                )
        if sobol_samples is not None:
            from jointplay.studies.sobol import check_samples

            try:
                check_samples(sobol_samples)
            except ValueError as exc:
                words = str(exc).removeprefix("samples: ")
                raise OptionError(
                    f"--sobol-samples {sobol_samples}: {words}", source=source
                ) from None
        mode: Literal["auto", "always", "never"] = (
            "always" if variance == "always" else "never" if variance == "never" else "auto"
        )
        shares = MotionContributions(
            variance=mode, samples=1024 if sobol_samples is None else sobol_samples
        )
        chosen: Literal["auto", "model", "probes"] = (
            "model" if loads == "model" else "probes" if loads == "probes" else "auto"
        )
        _check_outputs(csv, plot)
        model = load(model_path)
        settings = Motion(drive=drive, range=bounds, steps=steps, case=case)
        with _progress_display(not as_json) as bar:
            nominal = _staged(bar, "solving the motion", lambda: settings.run(model, source))
            failed = any(not r.passed for result in nominal.results for r in result.requirements)
            studies = MotionStudiesResult(
                nominal,
                None
                if samples is None
                else _staged(
                    bar,
                    f"Monte Carlo: {samples} sets of parts at every pose",
                    lambda: MotionMonteCarlo(samples=samples, seed=seed, motion=settings).run(
                        model, workers=workers, source=source
                    ),
                ),
                MotionEnvelope(loads=chosen, motion=settings).run(
                    model,
                    source=source,
                    progress=_stage(bar, "envelopes at every pose", nominal.steps),
                )
                if envelope
                else None,
                dataclasses.replace(shares, motion=settings).run(
                    model,
                    source=source,
                    progress=_stage(bar, "contributions at every pose", nominal.steps),
                    workers=workers,
                )
                if contributions
                else None,
            )
        _finish_study(
            studies,
            csv,
            plot,
            lambda: _motion_plots().motion_figure(
                nominal,
                _motion_plots().MotionPictures(
                    *studies.picture_extras(), envelope_label=studies.envelope_label()
                ),
            ),
            as_json,
            lambda: render_motion(
                nominal, source, _console(), studies.columns(), studies.findings()
            ),
        )

    _guarded(run, as_json)
    if failed and fail_on_requirements:
        raise typer.Exit(REQUIREMENT_FAILED)


@app.command(short_help="Which toleranced play drives each functional point.")
def contributions(
    model_path: ModelPath,
    case: CaseOption = None,
    step: Annotated[
        float,
        typer.Option("--step", help="Difference step, as a fraction of each play's tolerance."),
    ] = 1e-3,
    csv: Annotated[
        Path | None,
        typer.Option("--csv", metavar="FILE", help="Write the table (measure x play) as CSV."),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the study as JSON.")] = False,
    plot: PlotOption = None,
    variance: Annotated[
        str,
        typer.Option(
            "--variance",
            metavar="auto|always|never",
            help="Shares of the variance (Sobol' indices): 'auto' where a measure is not "
            "linear over the ranges, 'always', or 'never'.",
        ),
    ] = "auto",
    samples: Annotated[
        int,
        typer.Option(
            "--samples",
            "-n",
            min=8,
            help="Sobol' base sets of parts, a power of 2 (it solves samples x (inputs + 2)).",
        ),
    ] = 1024,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Random seed.")] = 0,
    workers: WorkersOption = None,
) -> None:
    """Which toleranced play drives each functional point: sensitivities at the
    nominal plays and percent contributions, worst case and statistical (RSS),
    where the measure is linear over the ranges; where it is not, the shares of
    its variance (Sobol' first-order and total indices, with intervals)."""
    from jointplay.io.modelfile import load
    from jointplay.present.textreport import render_contributions
    from jointplay.studies.contributions import Contributions

    def run() -> None:
        source = str(model_path)
        try:
            settings = Contributions(step, case, variance, samples, seed)  # type: ignore[arg-type]
        except ValueError as exc:
            raise OptionError(f"--{exc}", source=source) from None
        _check_outputs(csv, plot)
        model = load(model_path)
        result = settings.run(model, source=source, workers=workers)
        _finish_study(
            result,
            csv,
            plot,
            lambda: _plots().contributions_figure(result),
            as_json,
            lambda: render_contributions(result, source, _console()),
        )

    _guarded(run, as_json)


@app.command(short_help="Each requirement: worst case, RSS and Monte Carlo side by side.")
def tolerances(
    model_path: ModelPath,
    samples: Annotated[
        int, typer.Option("--samples", "-n", min=2, help="Monte Carlo samples.")
    ] = 100_000,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Random seed.")] = 0,
    confidence: Annotated[
        float,
        typer.Option("--confidence", help="Confidence level of the Monte Carlo ppm interval."),
    ] = 0.95,
    case: CaseOption = None,
    workers: WorkersOption = None,
    csv: Annotated[
        Path | None,
        typer.Option("--csv", metavar="FILE", help="Write the table (one row per requirement)."),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the study as JSON.")] = False,
    plot: PlotOption = None,
) -> None:
    """Each requirement three ways, side by side: the worst case (the greatest
    over every combination of the tolerances' limits, each a certified
    equilibrium), RSS with Cp/Cpk and ppm where the measure is linear, and Monte
    Carlo with Pp/Ppk and ppm (docs/tolerancing.md says which holds when)."""
    from jointplay.io.modelfile import load
    from jointplay.present.textreport import render_tolerances
    from jointplay.studies.tolerances import Tolerances

    def run() -> None:
        source = str(model_path)
        if not 0 < confidence < 1:
            raise OptionError("--confidence: between 0 and 1 (0.95 is 95 %)", source=source)
        _check_outputs(csv, plot)
        model = load(model_path)
        result = Tolerances(samples, seed, confidence, case).run(
            model, workers=workers, source=source
        )
        _finish_study(
            result,
            csv,
            plot,
            lambda: _plots().tolerances_figure(result),
            as_json,
            lambda: render_tolerances(result, source, _console()),
        )
        _at_written_pose(model, source, as_json)

    _guarded(run, as_json)


@app.command(short_help="Draw the solved mechanism and its joints (PNG, SVG, PDF).")
def plot(
    model_path: ModelPath,
    output: Annotated[
        Path,
        typer.Option("--output", "-o", metavar="FILE", help="Figure file: .png, .svg or .pdf."),
    ],
    case: CaseOption = None,
    magnify: Annotated[
        float | None,
        typer.Option(
            "--magnify",
            metavar="FACTOR",
            help="Multiply displacements and plays by this (default: a round factor that "
            "shows them as about 8 % of the mechanism).",
        ),
    ] = None,
    kind: Annotated[
        str,
        typer.Option(
            "--kind",
            metavar="mechanism|joints",
            help="'mechanism': 3D, the three views and every joint; 'joints': each joint "
            "at true size only.",
        ),
    ] = "mechanism",
    exact: Annotated[
        bool, typer.Option("--exact", help="Solve with exact rotations first.")
    ] = False,
) -> None:
    """Draw the solved MODEL in the paper's manner: the bodies as lines between
    their joints, initial and displaced (magnified), each joint's clearance
    domain, the contacts (red: touching), the contact forces and the loads, in
    3D and in the three views; and each joint seen along its axis."""
    from jointplay.io.modelfile import load
    from jointplay.solver.solve import Workspace

    def run() -> None:
        from jointplay.model.mechanism import check_case
        from jointplay.present.outputs import check_figure_path
        from jointplay.present.plot import clearance_figure, mechanism_figure, save

        source = str(model_path)
        if kind not in ("mechanism", "joints"):
            raise OptionError(f"--kind {kind!r}: expected 'mechanism' or 'joints'", source=source)
        _check_magnify(magnify, source)
        check_figure_path(output)
        model = load(model_path)
        check_case(model, case, source)
        chosen = _first_case(model, case)
        ws = Workspace.of(model)
        result = ws.solve(loads=None if chosen is None else model.loads_of(chosen), exact=exact)
        fig = (
            mechanism_figure(model, result, magnify=magnify, case=chosen)
            if kind == "mechanism"
            else clearance_figure(model, result)
        )
        save(fig, output)
        _note(f"wrote {output}")

    _guarded(run, False)


@app.command(short_help="One self-contained HTML page: model, solution, figures, studies.")
def report(
    model_path: ModelPath,
    output: Annotated[
        Path, typer.Option("--output", "-o", metavar="FILE", help="The page to write (.html).")
    ],
    case: Annotated[
        str | None,
        typer.Option("--case", metavar="NAME", help="Only this load case (default: every case)."),
    ] = None,
    magnify: Annotated[
        float | None,
        typer.Option("--magnify", metavar="FACTOR", help="The pictures' factor (default: round)."),
    ] = None,
    studies: Annotated[
        bool,
        typer.Option(
            "--studies/--no-studies",
            help="Each point's worst-case envelope and, when plays or loads vary, Monte Carlo "
            "and contributions.",
        ),
    ] = True,
    samples: Annotated[
        int, typer.Option("--samples", "-n", min=1, help="Monte Carlo: sets of parts.")
    ] = 10_000,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Monte Carlo: random seed.")] = 0,
    vary: VaryOption = None,
    rotate_load: RotateLoadOption = None,
    about: AboutOption = "z",
    steps: StepsOption = 72,
    start_deg: FromOption = 0.0,
    stop_deg: ToOption = None,
    exact: Annotated[bool, typer.Option("--exact", help="Solve with exact rotations.")] = False,
) -> None:
    """Write one self-contained HTML page of MODEL for a browser (works offline):
    the model, the solution of each load case with its contact forces, the
    figures, an interactive 3D view, and the studies (add a sweep with --vary or
    --rotate-load)."""
    from jointplay.io.modelfile import load
    from jointplay.present.report import Report

    def run() -> None:
        from jointplay.present.outputs import check_output_path

        source = str(model_path)
        fix = "a report is an HTML page; name the file .html"
        check_output_path(output, (".html", ".htm"), "-o", fix)
        _check_magnify(magnify, source)
        sweep = None
        if vary or rotate_load is not None:
            sweep = _sweep_settings(
                vary, rotate_load, about, steps, start_deg, stop_deg, case, 64, source
            )
        model = load(model_path)
        settings = Report(case, magnify, studies, samples, seed, sweep, exact)
        # progress on a terminal only (a pipe, a file or a CI log gets none)
        shown = Console(stderr=True).is_terminal
        page = settings.render(model, source, note=_note if shown else None)
        try:
            output.write_text(page, encoding="utf-8")
        except OSError as exc:
            raise OptionError(f"-o {output}: cannot write it ({exc.strerror})") from None
        _note(f"wrote {output} ({len(page) / 1e6:.1f} MB)")

    _guarded(run, False)


def _check_magnify(magnify: float | None, source: str) -> None:
    if magnify is not None and not 0.0 < magnify < float("inf"):
        raise OptionError(
            f"--magnify {magnify:g}: expected a factor above 0 (1 draws true size)",
            source=source,
        )


def _finish_study(
    result: Any,
    csv: Path | None,
    plot: Path | None,
    figure: Callable[[], Any],
    as_json: bool,
    render: Callable[[], None],
) -> None:
    """A study's outputs: the CSV table, the figure (``figure()`` draws it),
    each said on stderr ("wrote FILE") but with --json, then the JSON
    document or the readable report."""
    if csv is not None:
        try:
            result.to_dataframe().to_csv(csv, index=False)
        except OSError as exc:
            raise OptionError(f"--csv {csv}: cannot write it ({exc.strerror})") from None
        if not as_json:  # --json: stdout is the document, stderr stays quiet
            _note(f"wrote {csv}")
    if plot is not None:
        _save_plot(figure(), plot, said=not as_json)
    if as_json:
        typer.echo(_json(result.to_dict()))
    else:
        render()


def _plots() -> Any:
    from jointplay.present import plot

    return plot


def _motion_plots() -> Any:
    from jointplay.present import motion_plots

    return motion_plots


def _check_outputs(csv: Path | None, plot: Path | None) -> None:
    """A study's output files, before the work (which may take minutes)."""
    from jointplay.present.outputs import check_figure_path, check_file_path

    if csv is not None:
        check_file_path(csv, "--csv")
    if plot is not None:
        check_figure_path(plot, "--plot")


def _save_plot(fig: Any, path: Path, said: bool = True) -> None:
    from jointplay.present.plot import save

    save(fig, path)
    if said:
        _note(f"wrote {path}")


def sweep_envelopes(model: Any, source: str) -> dict[str, Any]:
    """Each point's envelope at the nominal plays (those a sweep solves with),
    for the sweep's figure; a point its joints leave free gets none, said."""
    from jointplay.studies.envelope import point_envelopes

    found, missing = point_envelopes(model, "mean", source=source)
    for name in missing:
        _note(f"point {name!r}: no envelope (the joints leave it free)")
    return found


def _no_point(model: Any, model_path: Path) -> JointplayError:
    """The error of ``envelope`` without ``--point``: the points to choose from."""
    if not model.points:
        return StudyError(
            "the envelope bounds a functional point, and the model has none; add "
            "'points: [{name: tip, body: ..., at: [x, y, z]}]'",
            source=str(model_path),
        )
    names = ", ".join(repr(p.name) for p in model.points)
    return OptionError(f"--point: name the point to bound, one of {names}", source=str(model_path))


def _first_case(model: Any, case: str | None) -> str | None:
    """``case``, or the model's first load case (said on stderr) when it has some."""
    if case is not None or not model.case_names:
        return case
    first = model.case_names[0]
    others = ", ".join(repr(n) for n in model.case_names[1:])
    _note(
        f"drew load case {first!r}, the first"
        + (f" (others: {others})" if others else "")
        + "; choose one with --case"
    )
    return str(first)


def _note(text: str) -> None:
    Console(stderr=True, highlight=False, soft_wrap=True).print(f"jointplay: {text}", markup=False)


def _at_written_pose(model: Any, source: str, as_json: bool) -> None:
    """A study of one pose on a model with a ``motion``: say that its
    requirements were checked at the pose in the file only (the motion may
    fail them elsewhere in its cycle), and how to check them at every pose."""
    if as_json or model.motion is None or not model.requirements:
        return
    start, stop = model.motion.range
    _note(
        f"the requirements were checked at the pose written in {source} only; its motion "
        f"drives '{model.motion.drive}' from {start} to {stop}: "
        f"`jointplay motion {shlex.quote(source)}` "
        f"checks them at each of its {model.motion.steps} steps"
    )


def _with_progress(label: str, total: int, shown: bool, run: Callable[[Any], R]) -> R:
    """``run(progress)``, with a progress bar on stderr when ``shown`` and
    stderr is a terminal."""
    with _progress_display(shown) as bar:
        return run(_stage(bar, label, total))


@contextmanager
def _progress_display(shown: bool) -> Iterator[Any]:
    """A progress display on stderr (gone when done) when ``shown`` and stderr
    is a terminal, else None: a pipe, a file or a CI log gets no progress."""
    err = Console(stderr=True)
    if not shown or not err.is_terminal:
        yield None
        return
    from rich.progress import Progress

    with Progress(console=err, transient=True) as bar:
        yield bar


def _stage(bar: Any, label: str, total: int) -> Callable[[int, int], None] | None:
    """A task of ``bar`` (None: none), and its ``progress(done, total)``."""
    if bar is None:
        return None
    task = bar.add_task(label, total=total)
    return lambda done, total: bar.update(task, completed=done, total=total)


def _staged(bar: Any, label: str, run: Callable[[], R]) -> R:
    """``run()``, shown on ``bar`` (if any) as a task of unknown length while it runs."""
    if bar is None:
        return run()
    task = bar.add_task(label, total=None)
    try:
        return run()
    finally:
        bar.remove_task(task)


def _console() -> Console:
    # names from the model are printed as they are: "[/b]" is not markup, ":x:" no emoji
    console = Console(highlight=False, soft_wrap=False, markup=False, emoji=False)
    if not console.is_terminal:  # a pipe, a file, a CI log: no line is wrapped
        from jointplay.present.textreport import UNBROKEN

        console.width = UNBROKEN
    return console


def _error_doc(exc: JointplayError) -> dict[str, Any]:
    """``--json``'s document for an error: its status, kind and message (and
    for a mechanism not held, the body and the motion)."""
    status = {2: "invalid", 3: "unbounded"}.get(exc.exit_code, "error")
    doc: dict[str, Any] = {"status": status, "kind": exc.label, "message": str(exc)}
    if isinstance(exc, UnboundedMechanismError):
        doc.update(body=exc.body, motion=exc.motion)
    return doc


def _say(exc: JointplayError) -> None:
    """An error's one line on stderr, in jointplay's words."""
    Console(stderr=True, highlight=False, soft_wrap=True).print(
        f"jointplay: {exc.label}: {exc}", markup=False
    )


def _guarded(run: Any, as_json: bool) -> None:
    err = Console(stderr=True, highlight=False, soft_wrap=True)
    try:
        with warnings.catch_warnings():
            # numpy's overflow and division warnings on extreme models are noise
            # around the one message: the certificate decides what is printed
            if not os.environ.get("JOINTPLAY_DEBUG"):
                warnings.simplefilter("ignore", RuntimeWarning)
            run()
    except JointplayError as exc:
        if as_json:
            typer.echo(_json(_error_doc(exc)))
        _say(exc)
        raise typer.Exit(exc.exit_code) from None
    except (typer.Exit, typer.Abort, KeyboardInterrupt):
        raise
    except Exception as exc:  # a bug in jointplay, not in the input
        if as_json:
            typer.echo(json.dumps({"status": "error", "message": f"internal error: {exc}"}))
        if os.environ.get("JOINTPLAY_DEBUG"):
            traceback.print_exc()
        err.print(
            f"jointplay: internal error ({type(exc).__name__}: {exc}). This is a bug in "
            "jointplay; set JOINTPLAY_DEBUG=1 to see the traceback, and please report it.",
            markup=False,
        )
        raise typer.Exit(1) from None


def main() -> None:
    """The command line: a usage error (an unknown option, a value out of
    range) is reported in jointplay's words, as "invalid option", exit 2."""
    try:
        code = app(standalone_mode=False)
    except Exception as exc:
        # by name: newer Typer releases raise these from their own copy of Click
        kinds = {cls.__name__ for cls in type(exc).__mro__}
        if "NoArgsIsHelpError" in kinds:  # plain 'jointplay': the help
            typer.echo(exc.format_message())  # type: ignore[attr-defined]
            sys.exit(0)
        if "UsageError" in kinds:
            ctx = getattr(exc, "ctx", None)
            hint = f" (see '{ctx.command_path} --help')" if ctx is not None else ""
            message = f"{exc.format_message()}{hint}"  # type: ignore[attr-defined]
            if "--json" in sys.argv[1:]:  # --json's output parses, whatever went wrong
                doc = {"status": "invalid", "kind": "invalid option", "message": message}
                typer.echo(_json(doc))
            Console(stderr=True, highlight=False, soft_wrap=True).print(
                f"jointplay: invalid option: {message}", markup=False
            )
            sys.exit(2)
        if "Abort" in kinds:  # Ctrl-C at a prompt
            sys.exit(1)
        raise
    sys.exit(code if isinstance(code, int) else 0)


if __name__ == "__main__":  # pragma: no cover
    main()
