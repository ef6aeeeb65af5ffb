"""The one front door of an estimate: what the user asked for, checked once (:class:`EstimateRequest`).

:func:`wbsa.estimate`, ``wbsa estimate`` and ``wbsa serve`` build the request the same way
(:meth:`EstimateRequest.build`); below it nothing is looked up or checked again: the camera travels as its
record (:class:`wbsa.camera.presets.CameraRecord`: intrinsics, working range, technology) with the noise model
the estimator assumes for it (:func:`wbsa.sensor.technology.envelope_model`), the clothes as a
:class:`~wbsa.estimation.clothes.Clothes`, the stature and the view as checked numbers.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

import numpy as np

from wbsa.errors import WbsaError
from wbsa.estimation.clothes import Clothes
from wbsa.estimation.subject.settings import SegmentSettings
from wbsa.typing import Method

if TYPE_CHECKING:  # pragma: no cover
    from wbsa.camera.presets import CameraRecord
    from wbsa.estimation.methods.base import Request
    from wbsa.estimation.methods.body_fit.settings import BodyFitSettings
    from wbsa.sensor.technology import SensorModel


@dataclass(frozen=True)
class EstimateRequest:
    """One estimate as asked for, every part checked (make it with :meth:`build`).

    Attributes
    ----------
    camera : CameraRecord or None
        The camera's record (a preset's, or one of the user's own calibration with its technology unknown:
        :func:`wbsa.camera.presets.own_camera`); None until the image's size tells it (``auto``,
        :meth:`for_image`).
    sensor : SensorModel or None
        The depth-noise model the estimator assumes for that camera (:func:`wbsa.sensor.technology.envelope_model`).
    camera_assumed : bool
        The camera was ``auto``: the preset of the image's size (flagged ``camera_assumed``).
    method : {'regression', 'body-fit', 'both'}
    level : float
        Coverage of the prediction interval, in (0, 1).
    azimuth_deg, elevation_deg : float or None
        A stated view (degrees).
    clothes : Clothes
        What was stated of the clothes (:func:`wbsa.estimation.clothes.stated_clothes`).
    stature_m : float or None
        A stated stature (m), a human height (:data:`wbsa.estimation.limits.LIMITS`).
    segment : SegmentSettings or None
        How the subject is found in a room; None: every return is the subject.
    body_fit : BodyFitSettings or None
        The body fit's settings (``body-fit`` and ``both``; None: the defaults).
    """

    camera: CameraRecord | None
    sensor: SensorModel | None
    camera_assumed: bool
    method: Method
    level: float
    azimuth_deg: float | None
    elevation_deg: float | None
    clothes: Clothes
    stature_m: float | None
    segment: SegmentSettings | None
    body_fit: BodyFitSettings | None = None

    @classmethod
    def build(cls, camera, method: Method = "regression", *, azimuth_deg: float | None = None,
              elevation_deg: float | None = None, clothes: str | None = None, clothing_m: float | None = None,
              stature_m: float | None = None, level: float = 0.95,
              segment: SegmentSettings | None = SegmentSettings(),
              body_fit: BodyFitSettings | None = None) -> EstimateRequest:
        """The checked request; ``camera="auto"`` is resolved by :meth:`for_image`.

        Parameters
        ----------
        camera, method, azimuth_deg, elevation_deg, clothes, clothing_m, stature_m, level, segment, body_fit
            As for :func:`wbsa.estimate` (a camera may also be a :class:`~wbsa.camera.presets.CameraRecord`).

        Returns
        -------
        EstimateRequest

        Raises
        ------
        WbsaError
            The first part that is wrong, in the order of the parameters (the camera last: a bad camera is
            refused before any image is read).
        """
        from wbsa.camera.presets import AUTO_CAMERA, resolve_record
        from wbsa.camera.views import check_angle
        from wbsa.estimation.clothes import stated_clothes
        from wbsa.estimation.methods.dispatch import check_method
        from wbsa.estimation.subject import checks

        check_method(method)
        if not (checks.is_real_number(level) and 0 < level < 1):
            raise WbsaError(f"interval level {level!r} must be a number in (0, 1), e.g. 0.95")
        if segment is not None and not isinstance(segment, SegmentSettings):
            raise WbsaError(f"segment must be SegmentSettings or None, got {type(segment).__name__}")
        if azimuth_deg is not None:
            azimuth_deg = check_angle(azimuth_deg, "azimuth", "azimuth_deg")
        if elevation_deg is not None:
            elevation_deg = check_angle(elevation_deg, "elevation", "elevation_deg")
        stated = stated_clothes(clothes, clothing_m)
        if stature_m is not None:
            stature_m = checks.check_stated_stature(stature_m)
        auto = isinstance(camera, str) and camera == AUTO_CAMERA
        record = None if auto else resolve_record(camera)
        return cls(record, None if record is None else _sensor(record), auto, method, float(level), azimuth_deg,
                   elevation_deg, stated, stature_m, segment, body_fit)

    def with_camera(self, record: CameraRecord) -> EstimateRequest:
        """This request with the camera ``record`` (one a point cloud brought), no longer assumed.

        Parameters
        ----------
        record : CameraRecord
        """
        return dataclasses.replace(self, camera=record, sensor=_sensor(record), camera_assumed=False)

    def for_image(self, depth_m: np.ndarray) -> EstimateRequest:
        """This request for a depth image: ``auto`` resolved to the preset of its size, which must be the
        camera's.

        Parameters
        ----------
        depth_m : (h, w) float64

        Raises
        ------
        WbsaError
            An image that is not 2-D, of a size no preset has (``auto``), or not the camera's size.
        """
        from wbsa.camera.presets import record_for_image
        from wbsa.estimation.subject import checks

        request = self
        if self.camera is None:
            checks.check_two_dimensional(depth_m)
            record = record_for_image(np.shape(depth_m))
            request = dataclasses.replace(self, camera=record, sensor=_sensor(record))
        checks.check_image_size(depth_m, request.camera.intrinsics)
        return request

    def method_request(self, progress: Callable[[str, int, int], None] | None = None) -> Request:
        """What a method is told (:class:`wbsa.estimation.methods.base.Request`): the view, the clothes' layer,
        the level, and the body fit's progress.

        Parameters
        ----------
        progress : callable, optional
            ``progress(stage, done, total)`` of :func:`wbsa.estimate`; the body fit's steps reach it as
            ``progress("body-fit", step, steps)``.
        """
        from wbsa.estimation.methods.base import Request

        return Request(self.azimuth_deg, self.elevation_deg, self.clothes.layer_m, self.level,
                       progress=None if progress is None else lambda step, steps: progress("body-fit", step, steps))


def _sensor(record):
    """The noise model the estimator assumes for ``record`` (:func:`wbsa.sensor.technology.envelope_model`)."""
    from wbsa.sensor.technology import envelope_model

    return envelope_model(record)


__all__ = ["EstimateRequest"]
