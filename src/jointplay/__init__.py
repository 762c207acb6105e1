"""jointplay: where the parts of a mechanism really sit when its joints have play.

>>> import jointplay
>>> model = jointplay.load("examples/paper/6.1.6.1.yaml")
>>> result = jointplay.solve(model)
>>> result.joints["l1"].translation  # mm, in the joint frame
"""

from .batch import BatchSolution
from .errors import JointplayError, ModelError, SolverError, UnboundedMechanismError
from .joints import JOINT_TYPES, Joint
from .model import Body, Load, Model
from .modelfile import load, model_from_dict
from .result import BodyResult, Certificate, ContactResult, JointResult, Result
from .solver import SolverSettings, Workspace, solve, solve_cases

__version__ = "0.1.0"

__all__ = [
    "JOINT_TYPES",
    "BatchSolution",
    "Body",
    "BodyResult",
    "Certificate",
    "ContactResult",
    "Joint",
    "JointResult",
    "JointplayError",
    "Load",
    "Model",
    "ModelError",
    "Result",
    "SolverError",
    "SolverSettings",
    "UnboundedMechanismError",
    "Workspace",
    "__version__",
    "load",
    "model_from_dict",
    "solve",
    "solve_cases",
]
