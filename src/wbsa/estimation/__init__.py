"""estimate stage: WBSA of a real person from one depth image and a fitted model file.

``segment`` isolates the subject in a real depth image (range gate, floor/wall planes, largest
connected region); ``single_view`` reconstructs the visible surface, measures its area (VBSA) and
predicts WBSA with a prediction interval from a ``wbsa fit`` model file.
"""

from wbsa.estimation.segment import SegmentSettings, segment_subject
from wbsa.estimation.single_view import Estimate, estimate_wbsa

__all__ = ["Estimate", "SegmentSettings", "estimate_wbsa", "segment_subject"]
