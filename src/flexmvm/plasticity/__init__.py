"""Small-strain J2 (von Mises) plasticity of the solid elements: the material's plastic part
(material), the radial return at integration points (return_mapping), the internal force
and consistent tangent of a body (body), their compiled loops (kernels) and the numpy form
they are checked against (reference), static equilibrium by full Newton (static_newton) and
a rigid sphere pressed into a flat face by an active set (indentation)."""

from flexmvm.plasticity.body import BodyResponse, PlasticBody
from flexmvm.plasticity.indentation import Indentation, indent_with_sphere
from flexmvm.plasticity.material import J2Plasticity
from flexmvm.plasticity.return_mapping import PointResponse, PointState, radial_return
from flexmvm.plasticity.static_newton import Loading, StaticPath, solve_static

__all__ = [
    "BodyResponse",
    "Indentation",
    "J2Plasticity",
    "Loading",
    "PlasticBody",
    "PointResponse",
    "PointState",
    "StaticPath",
    "indent_with_sphere",
    "radial_return",
    "solve_static",
]
