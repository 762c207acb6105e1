"""The joint catalogue. Each module defines one joint type; importing the
package registers them all in ``JOINT_TYPES`` by their ``type`` name."""

from jointplay.model.joints.base import JOINT_TYPES, Contact, Joint
from jointplay.model.joints.cylindrical import Cylindrical
from jointplay.model.joints.planar import Planar
from jointplay.model.joints.point import PointOnPlane
from jointplay.model.joints.prismatic import Prismatic
from jointplay.model.joints.revolute import Revolute
from jointplay.model.joints.rigid import Rigid
from jointplay.model.joints.slot import Slot
from jointplay.model.joints.sphere_in_cylinder import SphereInCylinder
from jointplay.model.joints.spherical import Spherical

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
    "Slot",
    "SphereInCylinder",
    "Spherical",
]
