"""bodies stage: virtual bodies (anny), skin mask, anthropometry, body composition, postures, populations.

``body_model``        :class:`BodyModel`: anny bodies, skin-only, standing on z = 0
``anthropometry``     :class:`Anthropometer`: stature, volume, mass, BMI, WBSA, tape measures
``composition``       fat fraction (Deurenberg 1991) and density (Siri, Brozek): :class:`CompositionSettings`
``posture``, ``posing``, ``posture_table``   named standing postures, posed by anny's skinning weights
``random_population`` the paper's Virtual Random (and varied shapes)
``survey*``           bodies matched to NHANES people (the paper's Virtual NHANES)
``table``, ``build``  the population table (:func:`build_population`, :func:`read_population`)
``settings``          :class:`PopulationSettings`
``make``              the notebook calls :func:`population` and :func:`body`

Names are imported lazily (anny and torch only when a body is built).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from wbsa.lazy import lazy_exports

if TYPE_CHECKING:  # pragma: no cover - real types for IDEs
    from wbsa.bodies.anthropometry import Anthropometer
    from wbsa.bodies.body_model import BodyModel
    from wbsa.bodies.build import build_population
    from wbsa.bodies.composition import CompositionSettings
    from wbsa.bodies.make import body, population
    from wbsa.bodies.posing import pose_vertices
    from wbsa.bodies.posture import PostureSettings
    from wbsa.bodies.posture_table import add_postures
    from wbsa.bodies.random_population import sample_random_parameters
    from wbsa.bodies.settings import PopulationSettings
    from wbsa.bodies.subject import subject_mesh
    from wbsa.bodies.survey import build_survey_population
    from wbsa.bodies.table import read_population

_EXPORTS = {
    "Anthropometer": "wbsa.bodies.anthropometry",
    "BodyModel": "wbsa.bodies.body_model",
    "build_population": "wbsa.bodies.build",
    "CompositionSettings": "wbsa.bodies.composition",
    "body": "wbsa.bodies.make",
    "population": "wbsa.bodies.make",
    "pose_vertices": "wbsa.bodies.posing",
    "PostureSettings": "wbsa.bodies.posture",
    "add_postures": "wbsa.bodies.posture_table",
    "sample_random_parameters": "wbsa.bodies.random_population",
    "PopulationSettings": "wbsa.bodies.settings",
    "subject_mesh": "wbsa.bodies.subject",
    "build_survey_population": "wbsa.bodies.survey",
    "read_population": "wbsa.bodies.table",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
