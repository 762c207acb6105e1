"""The mechanism through its range of motion, with the play's effect at every pose.

``Motion(...).run(model)`` finds every body's pose at each step
(``kinematics.nominal_poses``), builds the model as posed there (joints'
centres carried by their second body and axes by their first, functional
points, loads' points, centres of mass, outlines and shared deviations'
points and frames moved with their bodies; a load's force and torque keep
their global directions unless it ``follows: body``, and its tables are
read at the step's drive value; gravity stays global) and solves the clearance
equilibrium of that posed model, each pose's Newton starting from the answer
at the pose before (``batch.follow``; the full solve where that is not the
optimum).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from jointplay.errors import ModelError, OptionError, UnboundedMechanismError
from jointplay.geometry import FloatArray
from jointplay.indeterminacy import Indeterminacy, steps_dict
from jointplay.io.modelfile import model_from_dict
from jointplay.model.fields import with_values
from jointplay.model.joints.base import HOLDS
from jointplay.model.mechanism import Load, Model
from jointplay.model.tables import DriveTable
from jointplay.result import Result
from jointplay.settings import MOTION, MotionSettings
from jointplay.studies.kinematics import Poses, moves_only_the_drive, nominal_poses

if TYPE_CHECKING:
    import pandas as pd

    from jointplay.proven import Resolution
    from jointplay.result import JointResult


def posed_model(model: Model, poses: Poses, step: int, source: str = "<model>") -> Model:
    """``model`` placed as its bodies are at ``step``, without its motion;
    its loads' tables read at the step's drive value. Each entry is moved
    rigidly with its body and the model is not validated again
    (``fields.with_values``): the file's model was, and the checks that
    depend on the pose (plays against the model's extent, a shared
    deviation's frames) are not run at each step. ``source`` is kept for
    the callers' messages."""
    drive = float(poses.values[step])

    def at(body: str, X: Any) -> tuple[float, float, float]:
        x, y, z = (float(c) for c in poses.place(step, body, np.asarray(X, dtype=float)))
        return (x, y, z)

    def turned(body: str, v: Any) -> tuple[float, float, float]:
        x, y, z = (float(c) for c in poses.turn(step, body) @ np.asarray(v, dtype=float))
        return (x, y, z)

    joints = []
    for joint in model.joints:
        a, b = joint.between
        placement = {"at": at(b, joint.at)}  # a sliding joint's centre travels with its slider
        for key in ("axis", "up", "along"):
            if getattr(joint, key, None) is not None:
                placement[key] = turned(a, getattr(joint, key))
        joints.append(joint.placed(**placement))
    points = tuple(with_values(p, at=at(p.body, p.at)) for p in model.points)
    bodies = []
    for body in model.bodies:
        moved: dict[str, Any] = {}
        if body.center_of_mass is not None:
            moved["center_of_mass"] = at(body.name, body.center_of_mass)
        if body.outline is not None:
            moved["outline"] = tuple(at(body.name, X) for X in body.outline)
        bodies.append(with_values(body, **moved) if moved else body)
    deviations = []
    for dev in model.deviations:
        # features made together on one body: their point and frame move with it
        moved = {"at": at(dev.body, dev.at)}
        for key in ("axis", "up"):
            if getattr(dev, key) is not None:
                moved[key] = turned(dev.body, getattr(dev, key))
        deviations.append(with_values(dev, **moved))

    def posed_loads(loads: tuple[Load, ...]) -> tuple[Load, ...]:
        out = []
        for load in loads:
            moved: dict[str, Any] = {}
            if load.at is not None:
                moved["at"] = at(load.body, load.at)
            for key in ("force", "torque"):
                value = getattr(load, key)
                if value is None:
                    continue
                # a table over the drive's value, read at this step's value
                value = tuple(c.at(drive) if isinstance(c, DriveTable) else c for c in value)
                if load.follows == "body":
                    value = turned(load.body, [float(c) for c in value])  # a range's mean
                moved[key] = value
            posed = with_values(load, **moved)
            if load.follows == "body":
                # a range still varies along the body's axis it was given in
                posed._turned_ranges = tuple(
                    replace(part, direction=turned(load.body, part.direction))
                    for part in load.ranges()
                )
            out.append(posed)
        return tuple(out)

    cases = model.load_cases
    return with_values(
        model,
        bodies=tuple(bodies),
        joints=tuple(joints),
        points=points,
        deviations=tuple(deviations),
        loads=posed_loads(model.loads),
        load_cases=None if cases is None else {c: posed_loads(ld) for c, ld in cases.items()},
        motion=None,
    )


#: Between the names in a CSV cell of contacts (a name may hold spaces).
CELL_SEPARATOR = "; "

#: A touching contact's side: the directions of its force and of its torque
#: (None where it is 0 to the answer's resolution).
Side = tuple[FloatArray | None, FloatArray | None]


def _sides(jr: JointResult, resolution: Resolution) -> dict[str, Side]:
    def direction(v: FloatArray, zero: float) -> FloatArray | None:
        size = float(np.linalg.norm(v))
        return np.asarray(v) / size if size > zero else None

    return {
        c.name: (direction(c.force, resolution.force), direction(c.torque, resolution.moment))
        for c in jr.contacts
        if c.in_contact
    }


def switched_contacts(before: Result, now: Result, joint: str) -> tuple[str, ...]:
    """The contacts of ``joint`` that switch from the answer ``before`` to
    ``now``: one starts or stops touching, or one touching at both pushes the
    other way (its force, or its torque for a drive's backlash, turned by more
    than a quarter turn: the play crossed, where a running machine knocks). A
    force or torque below what its answer proves has no side. In the joint's
    order of contacts."""
    old = _sides(before.joints[joint], before.resolution)
    new = _sides(now.joints[joint], now.resolution)
    changed = set(old) ^ set(new)
    for name in set(old) & set(new):
        for u, w in zip(new[name], old[name], strict=True):
            if u is not None and w is not None and float(u @ w) < 0.0:
                changed.add(name)
    return tuple(c.name for c in now.joints[joint].contacts if c.name in changed)


def shown_drive(coordinate: str, value: float) -> float:
    """The drive's value as the user gives it: deg for a spin (to 12 digits:
    the turn from the range's degrees to radians and back leaves round-off,
    15 deg shown as 14.999999999999998), mm for a slide."""
    return float(f"{np.degrees(value):.12g}") if coordinate == "spin" else float(value)


@dataclass(frozen=True)
class MotionResult:
    """Per step: the drive's value, each point's nominal position and its
    displacement due to the play, each joint's torsor and reaction, the
    touching contacts, the drive's reaction, the requirements' measures."""

    model_name: str | None
    drive: str
    coordinate: str  # "spin" or "slide"
    values: FloatArray  # (S,) rad or mm
    poses: Poses
    point_names: tuple[str, ...]
    nominal: FloatArray  # (S, P, 3) mm
    displacement: FloatArray  # (S, P, 3) mm
    results: tuple[Result, ...]
    drive_reaction: FloatArray  # (S,) N*mm about the axis, or N along it (a on b)
    touching: tuple[tuple[str, ...], ...]
    requirement_names: tuple[str, ...]
    measured: FloatArray  # (S, Q) mm
    limits: FloatArray  # (Q,)
    case: str | None = None  # the load case the motion is under

    @property
    def steps(self) -> int:
        return len(self.values)

    @property
    def unit(self) -> str:
        return "deg" if self.coordinate == "spin" else "mm"

    def shown_value(self, s: int) -> float:
        return shown_drive(self.coordinate, float(self.values[s]))

    @property
    def reaction_unit(self) -> str:
        return "N*mm" if self.coordinate == "spin" else "N"

    @cached_property
    def switched(self) -> tuple[dict[str, tuple[str, ...]], ...]:
        """Per step, each joint's contacts that switch from the step before
        (``switched_contacts``; none at step 0), joints without one left out."""
        out: list[dict[str, tuple[str, ...]]] = [{}]
        for s in range(1, self.steps):
            before, now = self.results[s - 1], self.results[s]
            changes = {name: switched_contacts(before, now, name) for name in now.joints}
            out.append({name: names for name, names in changes.items() if names})
        return tuple(out[: self.steps])

    def worst_step(self, q: int) -> int:
        return int(np.argmax(self.measured[:, q]))

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(self.results[0].joints) if self.results else ()

    @property
    def indeterminate(self) -> tuple[Indeterminacy, ...]:
        """(S,) each step's static indeterminacy: where its contact forces
        are split by the rule, not decided by the balance."""
        return tuple(r.indeterminate for r in self.results)

    def to_dict(self) -> dict[str, Any]:
        steps = []
        for s, result in enumerate(self.results):
            steps.append(
                {
                    "drive": self.shown_value(s),
                    "points": {
                        name: {
                            "nominal": _list(self.nominal[s, k]),
                            "displacement": _list(self.displacement[s, k]),
                        }
                        for k, name in enumerate(self.point_names)
                    },
                    "joints": {
                        name: {
                            "translation": _list(j.translation),
                            "rotation": _list(j.rotation),
                            "reaction": {
                                "force": _list(j.reaction_force),
                                "moment": _list(j.reaction_moment),
                            },
                        }
                        for name, j in result.joints.items()
                    },
                    "drive_reaction": float(self.drive_reaction[s]),
                    "touching": list(self.touching[s]),
                    "switched": [
                        f"{joint}.{name}"
                        for joint, names in self.switched[s].items()
                        for name in names
                    ],
                    "requirements": [r.to_dict() for r in result.requirements],
                    "indeterminate": result.indeterminate.to_dict(),
                }
            )
        return {
            "study": "motion",
            "case": self.case,
            "drive": {
                "joint": self.drive,
                "coordinate": self.coordinate,
                "unit": self.unit,
                "reaction_unit": self.reaction_unit,
                "steps": self.steps,
            },
            "steps": steps,
            "requirements": [
                {
                    "point": name,
                    "max_displacement": float(self.limits[q]),
                    "worst_step": self.worst_step(q),
                    "measured": float(self.measured[self.worst_step(q), q]),
                    "passed": bool(np.all(self.measured[:, q] <= self.limits[q])),
                }
                for q, name in enumerate(self.requirement_names)
            ],
            "indeterminate": steps_dict(self.indeterminate, self.joint_names),
        }

    def to_dataframe(self) -> pd.DataFrame:
        import pandas as pd

        rows = []
        for s in range(self.steps):
            row: dict[str, Any] = {"step": s, f"drive ({self.unit})": self.shown_value(s)}
            for k, name in enumerate(self.point_names):
                for i, axis in enumerate("xyz"):
                    row[f"{name} {axis} (mm)"] = float(self.nominal[s, k, i])
                for i, axis in enumerate("xyz"):
                    row[f"{name} d{axis} (mm)"] = float(self.displacement[s, k, i])
            row[f"drive reaction ({self.reaction_unit})"] = float(self.drive_reaction[s])
            # names may hold spaces ("guide.z x- y-"): "; " between them
            row["touching"] = CELL_SEPARATOR.join(self.touching[s])
            row["switched"] = CELL_SEPARATOR.join(
                f"{joint}.{name}" for joint, names in self.switched[s].items() for name in names
            )
            # 0: the balance decides every force; above, the forces are the rule's split
            row["indeterminate degree"] = self.results[s].indeterminate.degree
            rows.append(row)
        return pd.DataFrame(rows)

    to_frame = to_dataframe


#: What holds a drive's coordinate in the clearance model: the field, and an example of it.


def _unheld(
    exc: UnboundedMechanismError, model: Model, poses: Poses, step: int, motion: Motion
) -> UnboundedMechanismError:
    """``exc``, a pose's "not held", saying so where what is free is the
    drive's own coordinate (its spin without a ``backlash``, its slide
    without an ``axial_clearance``: the drive holds nothing); otherwise
    ``exc`` as it was. The body, the motion and their directions are kept."""
    joint, coordinate, _, _ = model.motion_drive()
    field, example = HOLDS[coordinate].field, HOLDS[coordinate].example
    if getattr(joint, field, None) is not None or not moves_only_the_drive(
        model, poses, step, exc.direction, motion.settings
    ):
        return exc
    value = shown_drive(coordinate, float(poses.values[step]))
    unit = "deg" if coordinate == "spin" else "mm"
    verb = "turn" if coordinate == "spin" else "move"
    under = f" under load case '{motion.case}'" if motion.case else ""
    others = [repr(b) for b in exc.direction if b != exc.body]
    with_others = f" (together with {', '.join(others)})" if others else ""
    article = "an" if field[0] in "aeiou" else "a"
    return UnboundedMechanismError(
        f"at step {step} of the motion (drive '{joint.name}' at {value:g} {unit}){under} the "
        f"drive holds nothing: joint '{joint.name}' has no {field}, so its {coordinate} is "
        f"free and the loads {verb} it: body '{exc.body}': {exc.motion} is not held"
        f"{with_others}. A drive holds its {coordinate} up to its {field}: give "
        f"'{joint.name}' {article} {field} ({example}), or balance the loads on it.",
        body=exc.body,
        motion=exc.motion,
        direction=exc.direction,
    )


def _without_round_off(nominal: FloatArray, motion: Motion) -> FloatArray:
    """Nominal positions with components below what the kinematics closes to
    (``MotionSettings.closure`` of their size) as 0."""
    from jointplay.proven import proven

    size = float(np.max(np.abs(nominal), initial=0.0))
    return proven(nominal, motion.settings.closure * size)


def _list(v: FloatArray) -> list[float]:
    return [float(c) + 0.0 for c in v]


@dataclass(frozen=True)
class Motion:
    """Settings of a motion study: the model's ``motion`` section, or these
    in its place (``drive``: a joint; ``range``: start and stop as the
    section writes them; ``steps``)."""

    drive: str | None = None
    range: tuple[Any, Any] | None = None
    steps: int | None = None
    case: str | None = None
    settings: MotionSettings = MOTION

    def resolve(self, model: Model, source: str = "<model>") -> Model:
        """``model`` with its motion section replaced by these settings; an
        ``OptionError`` naming the option (``--case``, ``--steps``, ``--drive``,
        ``--range``) whose value does not fit the model."""
        self._check_case(model, source)
        given = {
            k: v
            for k, v in (("drive", self.drive), ("range", self.range), ("steps", self.steps))
            if v is not None
        }
        if self.steps is not None:
            from jointplay.model.motion import steps_problem

            problem = steps_problem(self.steps)
            if problem is not None:
                raise OptionError(f"--steps {self.steps}: {problem}", source=source)
        if self.drive is None and self.range is None:
            if model.motion is None:
                from jointplay.errors import StudyError

                raise StudyError(
                    "the model has no 'motion' section; add one, motion: {drive: JOINT, "
                    "range: ['0 deg', '360 deg'], steps: 73}, or give --drive and --range",
                    source=source,
                )
            if not given:
                return model
        section = {} if model.motion is None else model.motion.model_dump()
        section.update(given)
        self._check_given(model, section)
        data = model.model_dump(by_alias=True, exclude_none=True)
        data["motion"] = section
        try:
            return model_from_dict(data, source=source)
        except ModelError as exc:
            # the model was valid without these options: they do not fit it
            raise self._not_fitting(exc) from None

    def _not_fitting(self, exc: ModelError) -> OptionError:
        """``exc``, the model's error with the motion options given, as theirs."""
        given = [f"--drive {self.drive}"] if self.drive is not None else []
        if self.range is not None:
            given.append(f"--range '{self.range[0]}:{self.range[1]}'")
        if not given:
            return OptionError(exc.problem, source=exc.source)
        names = " and ".join(g.split(" ")[0] for g in given)
        where = f"the model file's {exc.entry}: " if exc.entry else ""
        return OptionError(
            f"{' '.join(given)}: {where}{exc.problem.rstrip('.')}, or give a {names} that "
            + ("fit it" if len(given) > 1 else "fits it"),
            source=exc.source,
        )

    def _check_case(self, model: Model, source: str) -> None:
        """The load case the motion is under: one of the model's, and given
        when the model has some (the top-level loads alone are no case of it)."""
        from jointplay.model.mechanism import check_case

        check_case(model, self.case, source, "the motion")

    def _check_given(self, model: Model, section: dict[str, Any]) -> None:
        """``OptionError`` naming ``--drive`` or ``--range`` when the value given
        here (the command line's) does not fit the model; what the file's
        motion section alone gets wrong is the file's error, said on loading."""
        from jointplay.model.mechanism import listing, suggest
        from jointplay.model.motion import (
            FILE_NAMES,
            OPTION_NAMES,
            MotionSection,
            coordinate_of,
            range_of,
        )

        names = [j.name for j in model.joints]
        if self.drive is not None and self.drive not in names:
            raise OptionError(
                f"--drive {self.drive}: unknown joint; joints are: {listing(names)}; name the "
                "joint whose spin or slide drives the motion." + suggest(self.drive, names)
            )
        if self.drive is None and self.range is None:
            return
        if "drive" not in section:
            raise OptionError(
                "--range: the model has no motion drive; give --drive JOINT, the joint whose "
                f"spin or slide drives the motion, one of {listing(names)}"
            )
        if section["drive"] not in names:
            return  # the file's unknown drive: the file's error
        if "range" not in section:
            raise OptionError(
                f"--drive {self.drive}: the model has no motion range; give --range "
                "START:STOP, e.g. --range '0 deg:360 deg'"
            )
        where = OPTION_NAMES if self.range is not None else FILE_NAMES
        try:
            start, stop = section["range"]
            joint = model.joint(section["drive"])
            kind = coordinate_of(joint, start, stop, where)
            range_of(MotionSection(**section), kind, where, joint.type_name)
        except ValueError as exc:
            if self.range is not None:
                raise OptionError(str(exc)) from None
            raise OptionError(
                f"--drive {self.drive}: the model file's motion {exc}; give --range START:STOP "
                "in the unit of the drive's coordinate"
            ) from None

    def run(self, model: Model, source: str = "<model>") -> MotionResult:
        from jointplay.assembly import assemble
        from jointplay.solver.batch import Start, extrapolated, follow
        from jointplay.solver.solve import Workspace

        model = self.resolve(model, source)
        assert model.motion is not None
        joint, coordinate, start, stop = model.motion_drive()
        values = np.linspace(start, stop, model.motion.steps)
        poses = nominal_poses(model, values, settings=self.settings, source=source)
        results, nominal, touching, reaction = [], [], [], []
        # each pose's Newton starts from the answers at the two poses before
        before: Start | None = None
        last: Start | None = None
        for s in range(len(values)):
            posed = posed_model(model, poses, s, source)
            loads = posed.loads_of(self.case) if self.case else None
            ws = Workspace(assemble(posed))
            try:
                result, after = follow(ws, extrapolated(before, last), loads)
            except UnboundedMechanismError as exc:
                raise _unheld(exc, model, poses, s, self) from None
            before, last = last, after
            results.append(result)
            nominal.append([poses.place(s, p.body, np.array(p.at)) for p in model.points])
            touching.append(
                tuple(
                    f"{name}.{c.name}"
                    for name, j in result.joints.items()
                    for c in j.contacts
                    if c.in_contact
                )
            )
            held = result.joints[joint.name]
            reaction.append(
                held.reaction_moment[0] if coordinate == "spin" else held.reaction_force[0]
            )
        names = tuple(p.name for p in model.points)
        P = len(names)
        disp = np.array(
            [[r.points[n].displacement for n in names] for r in results], dtype=float
        ).reshape(len(values), P, 3)
        measured = np.array(
            [[q.measured for q in r.requirements] for r in results], dtype=float
        ).reshape(len(values), len(model.requirements))
        return MotionResult(
            model.name,
            joint.name,
            coordinate,
            values,
            poses,
            names,
            _without_round_off(np.array(nominal, dtype=float).reshape(len(values), P, 3), self),
            disp,
            tuple(results),
            np.array(reaction, dtype=float),
            tuple(touching),
            tuple(q.point for q in model.requirements),
            measured,
            np.array([q.max_displacement for q in model.requirements], dtype=float),
            self.case,
        )
