"""The image → measured subject path every method starts from.

``mixed_pixels`` returns between two surfaces at a depth edge, snapped to one (:func:`repair_mixed_pixels`)
``room``         the floor and the walls among the largest planes (:func:`~.room.find_room`)
``segment``      the subject in a room: floor, walls behind, 3-D clusters (:func:`segment_subject`, :func:`find_people`)
``frame``        the image's frame: its border moved in past bands without returns
``people``       which objects are people (split by their heads when they touch), the feet seen
``pick``         which person a pick chooses, or a one-line refusal
``clusters``     person-sized clusters: occluders merged, low returns attached, people split at their heads
``feet``         the feet grown down to the floor
``cloud``        planes, the floor cut and the body frame of a point cloud
``measure``      VBSA, stature, size and view cues of the subject's pixels (:func:`measure_subject`)
``checks``       one-line errors for what cannot be measured, the image's own flags
``settings``     :class:`SegmentSettings`, how the subject is told apart from the room

Imports no method (:mod:`wbsa.estimation.methods`). Names are imported lazily.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "repair_mixed_pixels": "wbsa.estimation.subject.mixed_pixels",
    "SegmentSettings": "wbsa.estimation.subject.settings",
    "Segmentation": "wbsa.estimation.subject.segment",
    "segment_subject": "wbsa.estimation.subject.segment",
    "find_people": "wbsa.estimation.subject.segment",
    "SubjectMeasures": "wbsa.estimation.subject.measure",
    "measure_subject": "wbsa.estimation.subject.measure",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
