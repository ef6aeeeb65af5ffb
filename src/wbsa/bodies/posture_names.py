"""Names of the standing postures (:mod:`wbsa.bodies.posture`), importable without numpy (the study settings check them)."""

from __future__ import annotations

from typing import Literal, get_args

#: A named posture (:data:`wbsa.bodies.posture.POSTURES` has one entry per name, in this order).
PostureName = Literal["a-pose", "arms-down", "arms-wide", "hands-on-hips", "elbows-bent", "feet-together",
                      "feet-apart"]
#: What a population's ``posture`` setting may be: a name, or ``mixed`` (a random name per subject).
PostureChoice = Literal["a-pose", "mixed", "arms-down", "arms-wide", "hands-on-hips", "elbows-bent",
                        "feet-together", "feet-apart"]
#: The names of :data:`PostureName`, in order.
POSTURE_NAMES: tuple[str, ...] = get_args(PostureName)
