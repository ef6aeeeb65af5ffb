"""wbsa: whole body surface area from a single depth view.

The plain Python API (everything a notebook needs; the ``wbsa`` command is a thin layer over it):

>>> import wbsa
>>> sorted(n for n in wbsa.__all__ if n[0].islower())
['body', 'bsa', 'estimate', 'population', 'render', 'train']

``wbsa.population(n, kind, seed)``       a table of virtual people (stature, mass, WBSA, tape measures)
``wbsa.body(table, subject_id)``         one body's skin mesh (or ``wbsa.body(gender=0, height=0.7)``)
``wbsa.render(mesh, camera, view)``      the virtual depth camera: depth image, visible areas, reconstruction
``wbsa.estimate(depth, camera, model)``  WBSA from one real depth image, with its interval and flags
``wbsa.train(settings, out)``            an estimator model for your own camera, distances or population
``wbsa.bsa("mosteller", 170, 70)``     the classical height/weight formulae (cm, kg → m²)
``wbsa.Study.from_toml(path).run(out)``  the whole study: population → scan → fit → report

The package is laid out like the pipeline, on top of a shared ``core``:

``core``        shared types and formats: TriangleMesh, DepthFrame, mesh and depth-image files
``bodies``      virtual bodies (anny), anthropometry, random and survey populations
``formulae``    classical BSA formulae (Du Bois, Mosteller, ...)
``camera``      pinhole intrinsics/extrinsics, view grids, ray casting, visible area
``sensor``      depth noise, quantisation, holes
``surface``     surface reconstruction from one depth view
``simulate``    one simulated view: camera → sensor → surface (shared by view, scan and report)
``scan``        scanning a population at many views, in parallel, resumable
``analysis``    per-view regression, cross-validation, diagnostics, formula comparison
``report``      figures and the HTML report
``study``       the end-to-end study (``wbsa run``)
``estimation``  WBSA of a real person from one depth image (the run-time path)
``training``    estimator models trained on virtual captures (``wbsa train``)
``testing``     the estimator's held-out benchmark test set
``cli``         the ``wbsa`` command

Names are imported on first use, so ``import wbsa`` is fast.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from wbsa.core.versions import WBSA_VERSION as __version__
from wbsa.lazy import lazy_exports

if TYPE_CHECKING:  # pragma: no cover - real types for IDEs and type checkers
    from wbsa.analysis.model_file import WbsaModel
    from wbsa.bodies.make import body, population
    from wbsa.camera.intrinsics import Intrinsics
    from wbsa.camera.views import View
    from wbsa.core.frame import DepthFrame
    from wbsa.core.mesh import TriangleMesh
    from wbsa.errors import WbsaError
    from wbsa.estimation import Estimate, estimate
    from wbsa.estimation.methods.regression.model import EstimatorModel
    from wbsa.estimation.subject.settings import SegmentSettings
    from wbsa.estimation.methods.body_fit.settings import BodyFitSettings
    from wbsa.formulae.compute import bsa
    from wbsa.sensor.settings import SensorSettings
    from wbsa.simulate.view import SimulatedView, render
    from wbsa.study.study import Study
    from wbsa.training.run import train
    from wbsa.training.settings import TrainSettings

_EXPORTS = {
    "body": "wbsa.bodies.make",
    "population": "wbsa.bodies.make",
    "render": "wbsa.simulate.view",
    "SimulatedView": "wbsa.simulate.view",
    "estimate": "wbsa.estimation",
    "Estimate": "wbsa.estimation",
    "EstimatorModel": "wbsa.estimation.methods.regression.model",
    "SegmentSettings": "wbsa.estimation.subject.settings",
    "BodyFitSettings": "wbsa.estimation.methods.body_fit.settings",
    "bsa": "wbsa.formulae.compute",
    "Study": "wbsa.study.study",
    "TriangleMesh": "wbsa.core.mesh",
    "DepthFrame": "wbsa.core.frame",
    "Intrinsics": "wbsa.camera.intrinsics",
    "View": "wbsa.camera.views",
    "SensorSettings": "wbsa.sensor.settings",
    "WbsaModel": "wbsa.analysis.model_file",
    "WbsaError": "wbsa.errors",
    "train": "wbsa.training.run",
    "TrainSettings": "wbsa.training.settings",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
