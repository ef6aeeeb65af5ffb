"""What every estimation method shares: the subject it starts from, the request, the prediction it returns and the
:class:`Predictor` interface (the role :mod:`wbsa.camera.backends`' protocol plays for the ray casters).

A method is a :class:`Predictor` in a package of its own under :mod:`wbsa.estimation.methods`;
:func:`~wbsa.estimation.methods.dispatch.predictors_for` is the one place that picks it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable, Protocol

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from wbsa.camera.presets import CameraRecord
    from wbsa.sensor.technology import SensorModel
    from wbsa.estimation.subject.cloud import Plane
    from wbsa.estimation.subject.measure import SubjectMeasures
    from wbsa.estimation.subject.unseen import UnseenLegs
    from wbsa.estimation.methods.view import ViewEstimate


@dataclass(frozen=True)
class Subject:
    """The subject of one depth image, segmented and measured: what every method starts from.

    Attributes
    ----------
    depth_m : (h, w) float64
        The depth image (metres, 0 = no return), mixed returns repaired.
    mask : (h, w) bool
        The subject's pixels (the segmentation).
    camera : CameraRecord
        The camera's record (its intrinsics, working range, technology), as the request resolved it
        (:class:`wbsa.estimation.request.EstimateRequest`).
    floor : Plane or None
        The detected floor in the camera frame.
    measures : SubjectMeasures
    sensor : SensorModel or None
        The depth-noise model assumed for the camera (the request's); None: that of a camera whose technology is
        unknown.
    unseen : UnseenLegs or None
        The body below the lowest seen returns, where the feet are not seen and the stature is stated
        (:mod:`wbsa.estimation.subject.unseen`); None: the whole body is seen.
    """

    depth_m: np.ndarray
    mask: np.ndarray
    camera: CameraRecord
    floor: Plane | None
    measures: SubjectMeasures
    sensor: SensorModel | None = None
    unseen: UnseenLegs | None = None


@dataclass(frozen=True)
class Request:
    """What the user states beside the image: the view (degrees, None = estimate it), the layer of clothes
    (m) and the interval's level; and where a long method reports its progress (``progress(step, steps)``, or
    None)."""

    azimuth_deg: float | None = None
    elevation_deg: float | None = None
    clothing_m: float = 0.0
    level: float = 0.95
    progress: Callable[[int, int], None] | None = field(default=None, compare=False, repr=False)


@dataclass(frozen=True)
class Prediction:
    """WBSA and its interval (m²), the view estimated and the view used (degrees), the model's name, its flags and,
    for a method that fits a whole body, the fitted body."""

    wbsa_m2: float
    wbsa_lo_m2: float
    wbsa_hi_m2: float
    view: ViewEstimate
    view_used: tuple[float, float]
    model_name: str
    flags: dict[str, str] = field(default_factory=dict)
    body: object = None


class Predictor(Protocol):
    """What a method does: predict WBSA of one subject."""

    name: str

    def check_request(self, request: Request) -> None:
        """Raise :class:`WbsaError` for a request this predictor cannot serve (before the image is measured).

        Parameters
        ----------
        request : Request
            The stated view, clothes and interval level.
        """

    def predict(self, subject: Subject, request: Request) -> Prediction:
        """WBSA of ``subject`` with its interval and flags.

        Parameters
        ----------
        subject : Subject
            The segmented, measured subject.
        request : Request
            The stated view, clothes and interval level.

        Returns
        -------
        Prediction
        """


__all__ = ["Prediction", "Predictor", "Request", "Subject"]
