"""What the operator should do about each flag of an estimate: one table beside :data:`~wbsa.estimation.subject.checks.FLAGS`.

The page shows, for every flag an estimate carries, the flag's meaning (``FLAGS``, the one place it is
written), the estimate's own detail (``Estimate.flags``) and the step below. A test checks that this table
names every flag and no other.
"""

from __future__ import annotations

#: Flag name -> what to do about it, in words a nurse can act on.
ADVICE: dict[str, str] = {
    "cut_off": "Step the person back from the edge of the picture, or turn the camera, so that the whole body "
               "from head to feet is inside the image; then take the picture again.",
    "no_floor": "Tilt the camera down a little so that some floor shows in front of the feet; the answer is "
                "more reliable with the floor in view.",
    "several_people": "Check that the outlined person is the one to measure; if not, click on the right person "
                      "in the depth picture.",
    "beyond_working_range": "Move the person (or the camera) to the camera's working distance, given in the "
                            "detail, and take the picture again.",
    "out_of_training_range": "The person or the picture is unlike those the model learned from; treat the answer "
                             "with caution and check it against a height-and-weight formula below.",
    "view_disagrees": "The view typed does not match the picture: check the azimuth and elevation you typed, or "
                      "leave them empty so that they are estimated.",
    "uncertain_view": "Type the azimuth if you know it (0 when the person faces the camera), or ask the person to "
                      "face the camera squarely and take the picture again.",
    "model_mismatch": "The model was made for another camera or distance; use the camera and distance it was "
                      "made for, or the default model.",
    "camera_assumed": "Choose the camera that took the picture (or upload its intrinsics JSON) if it is not "
                      "the one named.",
    "interval_unsure": "The range given may be too narrow; report it as approximate.",
    "mixed_pixels": "Stand the person well in front of a plain wall, or turn on the camera's flying-pixel "
                    "filter, and take the picture again.",
    "not_a_person": "Check the outline in the depth picture: it may be an object, not the person; click on the "
                    "person, or clear the space around them and take the picture again.",
    "feet_unsure": "Bring the person (or the camera) closer, within the distance given in the detail, and take "
                   "the picture again.",
    "methods_disagree": "The two methods do not agree: check the outline, the clothes and the posture (standing, "
                        "arms slightly away from the body), and take the picture again.",
    "body_fit_failed": "The body fit could not measure this picture (the detail says why); the regression's answer "
                       "is shown. Fix what the detail names to get both.",
    "no_interval": "The body fit gives no range here; use the regression's range, or report the value as "
                   "approximate.",
    "not_converged": "The body fit did not settle: take the picture again with the person standing still, "
                     "arms slightly away from the body.",
    "time_budget": "The body fit ran out of time; its body may be off. Take the picture again, or use the "
                   "regression.",
    "posture_at_limit": "Ask the person to stand upright, feet slightly apart, arms slightly away from the body, "
                        "and take the picture again.",
    "outside_model_range": "The person's shape is at the edge of what the body model can take; treat the body "
                           "fit's answer with caution and compare it with the regression.",
    "poor_fit": "The fitted body explains the picture poorly (clothes, something in front of the person, or not "
                "a person): check the outline and take the picture again.",
    "steep_view": "Put the camera at about chest height, level, and take the picture again.",
    "feet_not_seen": "The feet are not in the picture, so the height typed was used: step the person back, or "
                     "turn the camera down, so that the whole body and the floor under the feet show, and take "
                     "the picture again.",
    "clothes_unstated": "Say what the person wears (underwear, a thin gown, light clothes or street clothes): "
                        "clothes make the answer read high.",
}


def flag_rows(flags: dict[str, str]) -> list[dict[str, str]]:
    """The page's rows for an estimate's ``flags``: name, meaning, the estimate's detail, what to do.

    >>> flag_rows({"cut_off": "subject pixels on the image border"})[0]["meaning"]
    'the subject touches the image border and may be cut off'
    """
    from wbsa.estimation.subject.checks import FLAGS

    return [{"name": name, "meaning": FLAGS.get(name, name.replace("_", " ")), "detail": detail,
             "todo": ADVICE.get(name, "Check the picture and take it again if in doubt.")}
            for name, detail in flags.items()]
