"""The joint catalogue. Each module defines one joint type; importing the
package registers them all in ``JOINT_TYPES`` by their ``type`` name."""

from .base import JOINT_TYPES, Contact, Joint
from .cylindrical import Cylindrical
from .planar import Planar
from .point import PointOnPlane
from .prismatic import Prismatic
from .revolute import Revolute
from .rigid import Rigid
from .sphere_in_cylinder import SphereInCylinder
from .spherical import Spherical

__all__ = [
    "JOINT_TYPES",
    "Contact",
    "Cylindrical",
    "Joint",
    "Planar",
    "PointOnPlane",
    "Prismatic",
    "Revolute",
    "Rigid",
    "SphereInCylinder",
    "Spherical",
]
