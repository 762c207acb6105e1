"""One exception family for everything jointplay reports to a user.

Each error knows the command-line exit code it maps to, so the CLI never has
to guess: 2 for a model that cannot be read or is invalid, 3 for a mechanism
that its joints do not hold against the loads.
"""

from __future__ import annotations


class JointplayError(Exception):
    """Base class of every error jointplay raises on purpose."""

    exit_code: int = 1
    #: What the command line says before the message ("jointplay: LABEL: ...").
    label: str = "error"

    def __reduce__(self) -> tuple[object, ...]:
        # whole, fields and all, from a study's worker process: pickle's
        # default calls the class with the message alone, which the
        # keyword-only fields refuse (the pool then broke: exit 1)
        return (_rebuilt, (type(self), self.args, self.__dict__))


def _rebuilt(
    cls: type[JointplayError], args: tuple[object, ...], fields: dict[str, object]
) -> JointplayError:
    exc = cls.__new__(cls, *args)
    exc.args = args
    exc.__dict__.update(fields)
    return exc


class ModelError(JointplayError, ValueError):
    """The model (file or Python objects) is invalid.

    The message is one paragraph: where (file and entry), what is wrong
    (expected ..., got ...), and the fix.
    """

    exit_code = 2
    label = "invalid model"

    def __init__(self, message: str, *, source: str | None = None, entry: str | None = None):
        self.problem = message
        self.source = source
        self.entry = entry
        where = ": ".join(part for part in (source, entry) if part)
        super().__init__(f"{where}: {message}" if where else message)


class OptionError(ModelError):
    """A command-line option is invalid (an output path that cannot be
    written, a value out of range): exit code 2, like a model error, and
    labelled 'invalid option'."""

    label = "invalid option"


class StudyError(ModelError):
    """A valid model that lacks what a study needs: nothing that varies from
    part to part, no functional point, no requirement. Exit code 2, labelled
    'nothing to study': the model is fine, the study has nothing to work on."""

    label = "nothing to study"


class UnassembledError(ModelError):
    """The joints' deviations leave no position inside every clearance: the
    parts cannot be put together. ``joints`` names those the solver's
    certificate of infeasibility involves. Exit code 2, like a model error:
    the model's own numbers contradict each other."""

    def __init__(self, message: str, *, joints: tuple[str, ...], source: str | None = None):
        self.joints = joints
        super().__init__(message, source=source)


class UnboundedMechanismError(JointplayError):
    """The loads drive a motion that no joint limits: there is no equilibrium.

    ``body`` names the (first) body that moves, ``motion`` describes the free
    motion in words, and ``direction`` holds, per moving body, the driven
    small-displacement torsor ``(rotation, translation at the global origin)``.
    """

    exit_code = 3
    label = "not held"

    def __init__(
        self,
        message: str,
        *,
        body: str,
        motion: str,
        direction: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]],
    ):
        self.body = body
        self.motion = motion
        self.direction = direction
        super().__init__(message)

    def in_case(self, case: str) -> UnboundedMechanismError:
        """The same verdict, its message naming the load case it is under."""
        return UnboundedMechanismError(
            f"under load case '{case}': {self}",
            body=self.body,
            motion=self.motion,
            direction=self.direction,
        )


class SolverError(JointplayError):
    """The cone solver failed, or its answer could not be certified."""

    exit_code = 1


class MotionError(ModelError):
    """The mechanism cannot be driven through its ``motion``: at ``step``
    (the drive at ``value``, in its own unit) its ideal joints ``joints``
    cannot close (``kind`` "unreachable": no pose closes them at that drive
    value) or the drive no longer decides the pose (``kind`` "dead point": the
    linkage at a toggle, which the drive cannot pass), or, before any step,
    the drive cannot move at all (``kind`` "locked": ``joints`` hold the
    coordinate it would change, step 0). Exit code 2: the model's motion asks
    for what its linkage cannot do; the fix is its range, or its drive."""

    label = "cannot move"

    def __init__(
        self,
        message: str,
        *,
        kind: str,
        step: int,
        value: float,
        joints: tuple[str, ...],
        source: str | None = None,
    ):
        self.kind = kind
        self.step = step
        self.value = value
        self.joints = joints
        super().__init__(message, source=source, entry="motion")
