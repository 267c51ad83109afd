"""An independent audit of grasp proposals: shares no code with the service.

It imports nothing from ``models.*`` outside this package (nor ``workers``, ``service``, ``clients``): the hands
are located and modelled here (:mod:`.hands`: description files, :mod:`.kinematics`: pytorch-kinematics / MuJoCo
FK rooted at the palm with the descriptions' own joint couplings, :mod:`.geometry`: link meshes), and the checks
(:mod:`.check`: contact distances, penetration, friction cones, wrench / force closure) use numpy, scipy,
trimesh and MuJoCo only. :mod:`.objects` provides third-party object meshes and concave test shapes.
"""

from research.audit.check import audit_grasp, audit_many
from research.audit.geometry import LinkGeometry, pose_matrix
from research.audit.hands import AuditHand, HandSpec, hand_specs, load_hand
from research.audit.inside import InsideTest
from research.audit.objects import ThirdPartyObject, concave_test_shapes, sample_surface, third_party_objects
from research.audit.penetration import PenetrationAudit, measure_penetration
from research.audit.report import AuditedGrasp, AuditReport, ContactAudit
from research.audit.wrench import closure_epsilon, contact_wrenches, friction_components, in_cone, primitive_wrenches

__all__ = [
    "AuditHand",
    "AuditReport",
    "AuditedGrasp",
    "ContactAudit",
    "HandSpec",
    "InsideTest",
    "LinkGeometry",
    "PenetrationAudit",
    "ThirdPartyObject",
    "audit_grasp",
    "audit_many",
    "closure_epsilon",
    "concave_test_shapes",
    "contact_wrenches",
    "friction_components",
    "hand_specs",
    "in_cone",
    "load_hand",
    "measure_penetration",
    "pose_matrix",
    "primitive_wrenches",
    "sample_surface",
    "third_party_objects",
]
