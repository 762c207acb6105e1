"""Sweeps: the equilibrium as one entry of the model moves over a range.

A sweep varies numeric entries of the model, named by their path in the
model file (``loads[0].force[1]``, ``joints[l2].clearance``,
``points[B].at[0]``), each over its own values, and turns loads about an
axis in steps (a rotating unbalance, a crank cycle). Several parameters make
a grid: every combination is one step, the last parameter changing fastest.

Every step is a full, certified solve of the changed model. Steps that change
only the loads reuse the assembled workspace (its free motions and contact
faces), so a turning load costs about a millisecond a step. The table of a
sweep holds, per step, the functional points' displacements, the joints'
relative torsors and each contact's state and force.

Steps are solved in chunks, in this process, in local processes, or on a Dask
cluster; the answer is the same whichever way (each step is deterministic).
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from jointplay.errors import JointplayError, ModelError, OptionError, UnboundedMechanismError
from jointplay.geometry import FloatArray
from jointplay.indeterminacy import Indeterminacy, steps_dict
from jointplay.io.modelfile import model_from_dict
from jointplay.model.mechanism import Model, check_case
from jointplay.solver.solve import Workspace
from jointplay.studies.parallel import run_chunks
from jointplay.units import shown

if TYPE_CHECKING:
    import pandas as pd

#: The most steps one sweep may have (a grid multiplies its parameters' counts).
MAX_STEPS = 1_000_000
#: Entries of the model that only change the loads: the workspace is kept.
_LOAD_SECTIONS = ("loads", "load_cases", "gravity")
_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
_NUMBER = re.compile(r"\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*(.*?)\s*$")
_SEGMENT = re.compile(r"\.?([^.\[\]]+)|\[([^\[\]]*)\]")


# -- what varies ------------------------------------------------------------
@dataclass(frozen=True)
class Vary:
    """One entry of the model over its values. ``path``: where the entry is in
    the model file; ``values``: plain numbers (the file's base units: mm, N,
    N*mm, rad) or strings with a unit ("10 N")."""

    path: str
    values: tuple[float | str, ...]

    def __post_init__(self) -> None:
        parse_path(self.path)
        if not self.values:
            raise ValueError(f"{self.path}: no values to take")

    @classmethod
    def range(cls, path: str, start: float | str, stop: float | str, count: int) -> Vary:
        """``count`` evenly spaced values from ``start`` to ``stop`` (both taken)."""
        return cls(path, _linspace(path, start, stop, count))

    @classmethod
    def parse(cls, text: str) -> Vary:
        """``PATH=START:STOP:COUNT`` or ``PATH=V1,V2,...`` (values may carry units)."""
        path, sep, spec = text.partition("=")
        if not sep or not path.strip() or not spec.strip():
            raise ValueError(
                f"--vary {text!r}: write PATH=START:STOP:COUNT, for example "
                "'loads[0].force[1]=0:10:11' or 'joints[l2].clearance=0.1:0.3:5'"
            )
        path = path.strip()
        if ":" in spec:
            parts = spec.split(":")
            if len(parts) != 3:
                raise ValueError(
                    f"--vary {text!r}: expected START:STOP:COUNT after '=', three parts"
                )
            start, stop, count = (p.strip() for p in parts)
            try:
                n = int(count)
            except ValueError:
                raise ValueError(
                    f"--vary {text!r}: COUNT {count!r} is not a whole number of steps"
                ) from None
            return cls.range(path, _number_or_text(start), _number_or_text(stop), n)
        return cls(path, tuple(_number_or_text(v.strip()) for v in spec.split(",")))

    @property
    def label(self) -> str:
        unit = {_split_unit(v)[1] for v in self.values if isinstance(v, str)} - {""}
        return f"{self.path} ({unit.pop()})" if len(unit) == 1 else self.path

    def numbers(self) -> FloatArray:
        """The values as numbers, in the unit they were written in."""
        return np.array([_split_unit(v)[0] for v in self.values])


@dataclass(frozen=True)
class RotateLoad:
    """Turn load ``load`` (its index in the model's ``loads``) about ``about``
    (an axis through the origin: the force and torque vectors turn, the point
    of application stays) in ``steps`` equal steps over a full turn, or over
    ``start_deg`` to ``stop_deg`` (both taken) when ``stop_deg`` is given."""

    load: int
    about: tuple[float, float, float] = (0.0, 0.0, 1.0)
    steps: int = 72
    start_deg: float = 0.0
    stop_deg: float | None = None

    def __post_init__(self) -> None:
        if self.steps < 1:
            raise ValueError("--steps: at least 1")
        if not all(math.isfinite(c) for c in self.about) or not any(self.about):
            raise ValueError("--about: a non-zero axis, x, y, z or three numbers 'ax,ay,az'")

    @staticmethod
    def axis(text: str) -> tuple[float, float, float]:
        """``x``, ``y``, ``z`` (optionally signed) or ``ax,ay,az``."""
        t = text.strip().lower()
        sign = -1.0 if t.startswith("-") else 1.0
        if t.lstrip("+-") in _AXES:
            ax = _AXES[t.lstrip("+-")]
            return (sign * ax[0], sign * ax[1], sign * ax[2])
        try:
            parts = [float(p) for p in t.split(",")]
        except ValueError:
            parts = []
        if len(parts) != 3 or not all(math.isfinite(p) for p in parts) or not any(parts):
            raise ValueError(
                f"--about {text!r}: expected x, y, z or a non-zero axis 'ax,ay,az'"
            ) from None
        return (parts[0], parts[1], parts[2])

    @property
    def label(self) -> str:
        return f"loads[{self.load}] angle (deg)"

    def angles_deg(self) -> FloatArray:
        if self.stop_deg is None:
            return self.start_deg + 360.0 * np.arange(self.steps) / self.steps
        return np.linspace(self.start_deg, self.stop_deg, self.steps)


# -- the study --------------------------------------------------------------
@dataclass(frozen=True)
class Sweep:
    """Settings of a sweep; ``run`` returns a ``SweepResult``.

    ``vary``: entries of the model and their values; ``rotate``: a load that
    turns. With several, every combination is a step (a grid, the last
    parameter fastest; a rotation comes last). ``case``: the load case solved
    (needed when the model has load cases). ``chunk``: steps per task when run in
    parallel."""

    vary: tuple[Vary, ...] = ()
    rotate: RotateLoad | None = None
    case: str | None = None
    chunk: int = 64

    def __post_init__(self) -> None:
        if not self.vary and self.rotate is None:
            raise ValueError(
                "nothing to sweep: give --vary PATH=START:STOP:COUNT or --rotate-load N"
            )
        if self.chunk < 1:
            raise ValueError("chunk: at least 1")
        if self.steps > MAX_STEPS:
            raise ValueError(
                f"the sweep has {self.steps:,} steps, more than {MAX_STEPS:,}; use fewer values"
            )

    @property
    def labels(self) -> tuple[str, ...]:
        out = [v.label for v in self.vary]
        if self.rotate is not None:
            out.append(self.rotate.label)
        return tuple(out)

    @property
    def steps(self) -> int:
        n = math.prod(len(v.values) for v in self.vary)
        return n * (self.rotate.steps if self.rotate is not None else 1)

    def grid(self) -> list[tuple[int, ...]]:
        """Each step's index into each parameter's values."""
        sizes = [len(v.values) for v in self.vary]
        if self.rotate is not None:
            sizes.append(self.rotate.steps)
        return list(itertools.product(*(range(n) for n in sizes)))

    def run(
        self,
        model: Model,
        *,
        workers: int | None = 1,
        scheduler: str | None = None,
        progress: Callable[[int, int], None] | None = None,
        source: str | None = None,
    ) -> SweepResult:
        """Solve every step. ``workers``: local processes (None: one per core);
        ``scheduler``: a Dask scheduler address to solve the chunks on a cluster.
        ``progress(done, total)`` after each chunk; ``source``: the model
        file's name, for messages."""
        source = source or model.name or "<model>"
        base = _plain(model.model_dump(by_alias=True, exclude_none=True))
        self._check(model, base, source)
        grid = self.grid()
        chunks = [(lo, grid[lo : lo + self.chunk]) for lo in range(0, len(grid), self.chunk)]
        parts = _solve_chunks(base, self, chunks, workers, scheduler, source, progress)
        return _result(model, self, grid, parts)

    def _check(self, model: Model, base: dict[str, Any], source: str) -> None:
        """Every path names a number of the model, and every step is a valid
        model (checked on the first and the last step: a range's ends, and its
        unit)."""
        for v in self.vary:
            try:
                _locate(base, v.path)
            except ValueError as exc:
                raise OptionError(str(exc), source=source, entry=f"--vary {v.path}") from None
        if self.rotate is not None and not 0 <= self.rotate.load < len(model.loads):
            n = len(model.loads)
            raise OptionError(
                f"--rotate-load {self.rotate.load}: the model has {n} load"
                f"{'s' if n != 1 else ''} in 'loads' (counted from 0)"
                + (f"; give 0 to {n - 1}" if n > 1 else "; give 0" if n else "; add one to turn"),
                source=source,
            )
        check_case(model, self.case, source, "the sweep")
        for v in self.vary:
            # an entry of another case than the one solved would change nothing
            path = parse_path(v.path)
            if path[0] == "load_cases" and len(path) > 1 and path[1] != self.case:
                raise OptionError(
                    f"--vary {v.path}: that load acts in load case {shown(path[1])} only, and "
                    f"the sweep is under {shown(self.case)}; give --case {path[1]}",
                    source=source,
                )
        last = tuple(len(v.values) - 1 for v in self.vary)
        last += (self.rotate.steps - 1,) if self.rotate is not None else ()
        for index in dict.fromkeys(((0,) * len(last), last)):  # before any solve
            step_model(base, self, index, source)


#: How to give the sweep other values (after the entry's own fix, for the file).
VARY_FIX = "change the values given to --vary (a unit goes after the number: '0:10 N:11')"
ROTATE_FIX = "change the turn given to --rotate-load (--about, --from, --to), or the load it turns"


def step_model(base: dict[str, Any], sweep: Sweep, index: tuple[int, ...], source: str) -> Model:
    """The model at step ``index``; the model itself is valid, so where the
    step's is not, the option's values are wrong: an ``OptionError`` naming
    that option."""
    try:
        return model_from_dict(_step_data(base, sweep, index), source=source)
    except ModelError as exc:
        where = f"{exc.entry}: " if exc.entry else ""
        turned = _the_turn_breaks(base, sweep, index, source)
        raise OptionError(
            f"at the step {_step_name(sweep, index)}: {where}{exc.problem}; "
            f"{ROTATE_FIX if turned else VARY_FIX}",
            source=source,
            entry="--rotate-load" if turned else "--vary",
        ) from None


def _the_turn_breaks(
    base: dict[str, Any], sweep: Sweep, index: tuple[int, ...], source: str
) -> bool:
    """Whether the turn of --rotate-load makes step ``index`` invalid: the
    step's --vary values alone (if any) give a valid model."""
    if sweep.rotate is None:
        return False
    if not sweep.vary:
        return True
    try:
        model_from_dict(_step_data(base, replace(sweep, rotate=None), index[:-1]), source=source)
    except ModelError:
        return False
    return True


def parse_path(path: str) -> list[str | int]:
    """``loads[0].force[1]`` -> ``['loads', 0, 'force', 1]``; a bracket may
    hold a name (``joints[l2]``), which selects the entry of that name."""
    out: list[str | int] = []
    pos = 0
    text = path.strip()
    while pos < len(text):
        m = _SEGMENT.match(text, pos)
        if m is None or m.end() == pos:
            raise ValueError(f"cannot read the path {path!r} at {text[pos:]!r}")
        key = m.group(1) if m.group(1) is not None else m.group(2).strip().strip("'\"")
        if not key:
            raise ValueError(f"empty brackets in the path {path!r}")
        out.append(int(key) if re.fullmatch(r"-?\d+", key) else key)
        pos = m.end()
    if not out or not isinstance(out[0], str):
        raise ValueError(f"the path {path!r} must start with a section name, like loads[0]")
    return out


def _locate(data: dict[str, Any], path: str) -> tuple[Any, str | int]:
    """The container and key of the number at ``path``; ``ValueError`` names
    what is missing and what is there."""
    node: Any = data
    container: Any
    keys = parse_path(path)
    words = [k for k in keys if isinstance(k, str)]
    zoned = "deviation" in words or words[:1] == ["deviations"]
    if zoned and {"position", "orientation"} & set(words) and "mean" not in words:
        raise ValueError(
            "a zone's size changes no single solve (each step takes the zone at its "
            "mean); sweep its mean, like ...position.mean[1], or study the zone by Monte Carlo"
        )
    where = ""
    for n, key in enumerate(keys):
        last = n == len(keys) - 1
        if isinstance(node, dict):
            if key not in node:
                have = ", ".join(sorted(map(str, node))) or "nothing"
                raise ValueError(f"{where or 'the model'} has no {key!r}; it has: {have}")
            container, slot = node, key
        elif isinstance(node, list):
            if isinstance(key, int):
                if not -len(node) <= key < len(node):
                    raise ValueError(
                        f"{where} has {len(node)} entries; index {key} is out of range"
                        " (counted from 0)"
                    )
                slot = key
            else:
                names = [e.get("name") for e in node if isinstance(e, dict)]
                if key not in names:
                    known = ", ".join(str(x) for x in names if x is not None)
                    raise ValueError(
                        f"{where} has no entry named {key!r}"
                        + (f"; names are: {known}" if known else "; give its index")
                    )
                slot = names.index(key)
            container = node
        else:
            raise ValueError(f"{where} is a number, not a section; the path ends there")
        node = container[slot]
        if not where:
            where = str(key)
        else:
            where = f"{where}.{key}" if isinstance(container, dict) else f"{where}[{key}]"
        if last:
            if isinstance(node, bool) or not isinstance(node, int | float):
                raise ValueError(
                    f"{where} is not a number (it is {type(node).__name__}); vary one of "
                    f"its numbers, like {where}[0]"
                )
            return container, slot
    raise ValueError(f"empty path {path!r}")  # pragma: no cover - parse_path refuses it


def _plain(value: Any) -> Any:
    """A model dump with lists for tuples, so steps can be written into it."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def _split_unit(value: float | str) -> tuple[float, str]:
    if isinstance(value, int | float):
        return float(value), ""
    m = _NUMBER.match(value)
    if m is None:
        raise ValueError(f"{value!r} does not start with a number")
    return float(m.group(1)), m.group(2)


def _number_or_text(text: str) -> float | str:
    try:
        return float(text)
    except ValueError:
        return text


def _linspace(
    path: str, start: float | str, stop: float | str, count: int
) -> tuple[float | str, ...]:
    if count < 1:
        raise ValueError(f"--vary {path}: COUNT must be at least 1, got {count}")
    try:
        a, ua = _split_unit(start)
        b, ub = _split_unit(stop)
    except ValueError as exc:
        raise ValueError(f"--vary {path}: {exc}") from None
    if ua and ub and ua != ub:
        raise ValueError(
            f"--vary {path}: START is in {ua!r} and STOP in {ub!r}; write both in one unit"
        )
    unit = ua or ub
    values = [a] if count == 1 else np.linspace(a, b, count).tolist()
    return tuple(f"{v!r} {unit}" if unit else float(v) for v in values)


# -- solving the steps ------------------------------------------------------
@dataclass(frozen=True)
class _Chunk:
    start: int
    contact_names: tuple[tuple[str, str], ...]
    points: FloatArray  # (n, P, 3) mm
    translation: FloatArray  # (n, J, 3) mm, joint frames
    rotation: FloatArray  # (n, J, 3) rad
    gap_used: FloatArray  # (n, C)
    in_contact: np.ndarray[Any, np.dtype[np.bool_]]  # (n, C)
    force: FloatArray  # (n, C) N
    energy: FloatArray  # (n,) N*mm
    feasibility_mm: float
    equilibrium_residual: float
    reused: int  # steps solved on the previous step's workspace
    indeterminate: tuple[Indeterminacy, ...]  # (n,) whose forces are a convention


def _step_data(base: dict[str, Any], sweep: Sweep, index: tuple[int, ...]) -> dict[str, Any]:
    data: dict[str, Any] = _copy(base)
    for v, i in zip(sweep.vary, index, strict=False):
        container, slot = _locate(data, v.path)
        container[slot] = v.values[i]
    if sweep.rotate is not None:
        rot = sweep.rotate
        angle = math.radians(float(rot.angles_deg()[index[-1]]))
        R = _rotation(np.asarray(rot.about, dtype=float), angle)
        load = data["loads"][rot.load]
        for key in ("force", "torque"):
            if key in load:
                load[key] = (R @ np.asarray(load[key], dtype=float)).tolist()
    return data


def _copy(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _copy(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_copy(v) for v in value]
    return value


def _rotation(axis: FloatArray, angle: float) -> FloatArray:
    """Rodrigues: the rotation by ``angle`` about the unit ``axis``."""
    k = axis / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.asarray(np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * (K @ K))


def _without_loads(model: Model) -> Model:
    return model.model_copy(update={"loads": (), "load_cases": None, "gravity": None})


def _step_name(sweep: Sweep, index: tuple[int, ...]) -> str:
    parts = [f"{v.path} = {v.values[i]}" for v, i in zip(sweep.vary, index, strict=False)]
    if sweep.rotate is not None:
        parts.append(
            f"loads[{sweep.rotate.load}] turned {sweep.rotate.angles_deg()[index[-1]]:g} deg"
        )
    return ", ".join(parts)


def _own_verdict(
    model: Model, case: str | None, exc: UnboundedMechanismError
) -> UnboundedMechanismError:
    """The verdict of a solve of the step's own model: the workspace of a
    step before, whose loads were others, cannot name this step's loads by
    their entries."""
    try:
        Workspace.of(model).solve(model.loads_of(case))
    except UnboundedMechanismError as own:
        return own
    return exc  # not reached: the same mechanism under the same loads


def solve_steps(
    base: dict[str, Any], sweep: Sweep, start: int, steps: Sequence[tuple[int, ...]], source: str
) -> _Chunk:
    """The steps ``steps`` (indices into the parameters), solved in order."""
    rows: list[Any] = []
    ws: Workspace | None = None
    shape: Model | None = None
    reused = 0
    for index in steps:
        model = step_model(base, sweep, index, source)
        try:
            frame = _without_loads(model)
            if ws is not None and frame == shape:
                reused += 1
            else:
                ws, shape = Workspace.of(model), frame
            result = ws.solve(model.loads_of(sweep.case))
        except ModelError as exc:
            where = f"{exc.entry}: " if exc.entry else ""
            raise ModelError(
                f"at the step {_step_name(sweep, index)}: {where}{exc.problem}", source=source
            ) from None
        except UnboundedMechanismError as exc:
            if ws is not None and ws.asm.model is not model:
                exc = _own_verdict(model, sweep.case, exc)
            raise UnboundedMechanismError(
                f"at the step {_step_name(sweep, index)}: {exc}",
                body=exc.body,
                motion=exc.motion,
                direction=exc.direction,
            ) from None
        except JointplayError as exc:
            raise type(exc)(f"at the step {_step_name(sweep, index)}: {exc}") from None
        rows.append(result)
    first = rows[0]
    joints = list(first.joints)
    contacts = tuple((j, c.name) for j in joints for c in first.joints[j].contacts)
    return _Chunk(
        start,
        contacts,
        np.array([[p.displacement for p in r.points.values()] for r in rows]).reshape(
            len(rows), len(first.points), 3
        ),
        np.array([[r.joints[j].translation for j in joints] for r in rows]),
        np.array([[r.joints[j].rotation for j in joints] for r in rows]),
        np.array(
            [[c.gap_used for j in joints for c in r.joints[j].contacts] for r in rows]
        ).reshape(len(rows), len(contacts)),
        np.array(
            [[c.in_contact for j in joints for c in r.joints[j].contacts] for r in rows], dtype=bool
        ).reshape(len(rows), len(contacts)),
        np.array(
            [[c.force_magnitude for j in joints for c in r.joints[j].contacts] for r in rows]
        ).reshape(len(rows), len(contacts)),
        np.array([r.potential_energy for r in rows]),
        max(r.certificate.feasibility_mm for r in rows),
        max(r.equilibrium_residual for r in rows),
        reused,
        tuple(r.indeterminate for r in rows),
    )


def _solve_chunks(
    base: dict[str, Any],
    sweep: Sweep,
    chunks: list[tuple[int, list[tuple[int, ...]]]],
    workers: int | None,
    scheduler: str | None,
    source: str,
    progress: Callable[[int, int], None] | None,
) -> list[_Chunk]:
    total = sum(len(s) for _, s in chunks)
    done = [0]

    def advance(part: _Chunk) -> None:
        done[0] += len(part.energy)
        if progress is not None:
            progress(done[0], total)

    tasks = [(sweep, lo, s, source) for lo, s in chunks]
    return run_chunks(solve_steps, base, tasks, workers, scheduler, advance)


# -- the answer -------------------------------------------------------------
@dataclass(frozen=True)
class SweepResult:
    """Per step: the parameters' values, the points' displacements (mm, global
    axes), the joints' relative torsors (b relative to a at the joint centre,
    joint frame) and each contact's play used, state and force (N)."""

    settings: Sweep
    model_name: str | None
    labels: tuple[str, ...]  # one per parameter
    values: FloatArray  # (S, parameters), in the units of the labels
    point_names: tuple[str, ...]
    joint_names: tuple[str, ...]
    contact_names: tuple[tuple[str, str], ...]  # (joint, contact)
    points: FloatArray  # (S, P, 3)
    translation: FloatArray  # (S, J, 3)
    rotation: FloatArray  # (S, J, 3)
    gap_used: FloatArray  # (S, C)
    in_contact: np.ndarray[Any, np.dtype[np.bool_]]  # (S, C)
    force: FloatArray  # (S, C)
    potential_energy: FloatArray  # (S,)
    feasibility_mm: float  # worst over the steps
    equilibrium_residual: float  # worst over the steps
    #: (S,) each step's static indeterminacy: where its contact forces are
    #: split by the rule, not decided by the balance (``Result.indeterminate``)
    indeterminate: tuple[Indeterminacy, ...]

    @property
    def steps(self) -> int:
        return int(self.values.shape[0])

    def point(self, name: str) -> FloatArray:
        """(S, 3): point ``name``'s displacement at each step (mm)."""
        return self.points[:, self.point_names.index(name)]

    def to_dataframe(self) -> pd.DataFrame:
        """One row per step: the parameters, then points, joints and contacts."""
        import pandas as pd

        cols: dict[str, Any] = {"step": np.arange(self.steps)}
        for k, label in enumerate(self.labels):
            cols[label] = self.values[:, k]
        for p, name in enumerate(self.point_names):
            for c, axis in enumerate("xyz"):
                cols[f"{name}.d{axis}"] = self.points[:, p, c]
            cols[f"{name}.size"] = np.linalg.norm(self.points[:, p], axis=1)
        for j, name in enumerate(self.joint_names):
            for c, axis in enumerate("xyz"):
                cols[f"{name}.t{axis}"] = self.translation[:, j, c]
            for c, axis in enumerate("xyz"):
                cols[f"{name}.r{axis}"] = self.rotation[:, j, c]
        for c, (joint, contact) in enumerate(self.contact_names):
            cols[f"{joint}.{contact}.gap_used"] = self.gap_used[:, c]
            cols[f"{joint}.{contact}.in_contact"] = self.in_contact[:, c]
            cols[f"{joint}.{contact}.force"] = self.force[:, c]
        cols["potential_energy"] = self.potential_energy
        # 0: the balance decides every force; above, the forces are the rule's split
        cols["indeterminate_degree"] = [f.degree for f in self.indeterminate]
        return pd.DataFrame(cols)

    def to_dict(self) -> dict[str, Any]:
        steps = []
        for s in range(self.steps):
            joints: dict[str, Any] = {
                name: {
                    "translation": _list(self.translation[s, j]),
                    "rotation": _list(self.rotation[s, j]),
                    "contacts": [],
                }
                for j, name in enumerate(self.joint_names)
            }
            for c, (joint, contact) in enumerate(self.contact_names):
                joints[joint]["contacts"].append(
                    {
                        "name": contact,
                        "gap_used": float(self.gap_used[s, c]),
                        "in_contact": bool(self.in_contact[s, c]),
                        "force": float(self.force[s, c]),
                    }
                )
            steps.append(
                {
                    "values": {
                        label: float(self.values[s, k]) for k, label in enumerate(self.labels)
                    },
                    "points": {
                        name: _list(self.points[s, p]) for p, name in enumerate(self.point_names)
                    },
                    "joints": joints,
                    "potential_energy": float(self.potential_energy[s]),
                    "indeterminate": self.indeterminate[s].to_dict(),
                }
            )
        return {
            "study": "sweep",
            "model": self.model_name,
            "case": self.settings.case,
            "parameters": list(self.labels),
            "steps": steps,
            "certificate": {
                "feasibility_mm": self.feasibility_mm,
                "equilibrium_residual": self.equilibrium_residual,
            },
            "indeterminate": steps_dict(self.indeterminate, self.joint_names),
        }


def _list(v: FloatArray) -> list[float]:
    return [float(c) + 0.0 for c in v]


def _result(
    model: Model, sweep: Sweep, grid: list[tuple[int, ...]], parts: list[_Chunk]
) -> SweepResult:
    parts = sorted(parts, key=lambda c: c.start)
    columns = [v.numbers() for v in sweep.vary]
    if sweep.rotate is not None:
        columns.append(sweep.rotate.angles_deg())
    values = np.array([[columns[k][i] for k, i in enumerate(index)] for index in grid])
    contact_names = parts[0].contact_names
    for part in parts:
        if part.contact_names != contact_names:  # a joint type changed on the way
            raise ModelError("the steps of a sweep must keep each joint's contacts")
    return SweepResult(
        sweep,
        model.name,
        sweep.labels,
        values.reshape(len(grid), len(columns)),
        tuple(p.name for p in model.points),
        tuple(j.name for j in model.joints),
        contact_names,
        np.concatenate([c.points for c in parts]),
        np.concatenate([c.translation for c in parts]),
        np.concatenate([c.rotation for c in parts]),
        np.concatenate([c.gap_used for c in parts]),
        np.concatenate([c.in_contact for c in parts]),
        np.concatenate([c.force for c in parts]),
        np.concatenate([c.energy for c in parts]),
        max(c.feasibility_mm for c in parts),
        max(c.equilibrium_residual for c in parts),
        tuple(f for c in parts for f in c.indeterminate),
    )
