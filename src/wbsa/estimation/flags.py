"""Every flag an estimate can carry: one record each, its meaning, what to do about it and which routes raise it.

A flag is a name and a sentence in ``Estimate.flags`` (``warning: name: detail`` lines on the terminal, the
page's "check before you use the number" rows; a detail that is the fit's internals stays in the JSON, the
terminal saying the meaning and the advice instead: :func:`terminal_text`). The detail is the raiser's own (it carries the numbers and, on
the terminal, the fix in command-line terms); the meaning and the page's advice are here, once. Routes:
``image`` the estimate's own checks whatever the method (:mod:`wbsa.estimation.subject.checks`,
:func:`wbsa.estimation.single_view.estimate`), ``regression``, ``body-fit`` (its :class:`BodyFit` carries them
too) and ``both`` (the two side by side). A new flag is one record here; a test checks every flag raised is one.
"""

from __future__ import annotations

from dataclasses import dataclass

from wbsa.errors import Worded

_UNSTATED = ("no clothes were stated; they were taken as none or tight-fitting (clothes worn read high, about 9 % per "
             "cm of layer)")
#: The meaning (and detail) of ``clothes_unstated``: how to state them in Python, on the page, on the command line.
CLOTHES_UNSTATED = Worded(f"{_UNSTATED}: state them (clothes='underwear', 'thin-gown', 'light' or 'street')",
                          f"{_UNSTATED}: choose them under Clothes",
                          command=f"{_UNSTATED}: state them (--clothes underwear, thin-gown, light or street)")

_NO_FLOOR = ("no floor was found, so the feet could not be checked to stand on one (the elevation comes from the "
             "body's long axis)")
#: The meaning (and detail) of ``no_floor``: what to do with the image at hand, and next time.
NO_FLOOR = Worded(f"{_NO_FLOOR}: if the picture cuts off the legs, state the stature (--stature-cm); next time "
                  "tilt the camera down so the floor shows",
                  f"{_NO_FLOOR}: if the picture cuts off the legs, type the height; next time tilt the camera down "
                  "so the floor shows")


@dataclass(frozen=True)
class Flag:
    """One flag.

    Attributes
    ----------
    meaning : str
        What the flag means, in one line (:data:`FLAGS`).
    advice : str
        What to do about it, in words a nurse can act on (the page shows it).
    routes : tuple of str
        Which routes raise it: ``image``, ``regression``, ``body-fit``, ``both``.
    internal : bool
        Whether the raiser's detail is the fit's internals (parameter and joint names, residuals): the terminal
        then says the meaning and the advice instead (:func:`terminal_text`); the detail stays in the JSON.
    """

    meaning: str
    advice: str
    routes: tuple[str, ...]
    internal: bool = False


#: Flag name -> its record.
FLAG_RECORDS: dict[str, Flag] = {
    "cut_off": Flag(
        "the subject touches the image border and may be cut off",
        "Step the person back from the edge of the picture, or turn the camera, so that the whole body from head "
        "to feet is inside the image; then take the picture again.",
        ("image", "body-fit")),
    "no_floor": Flag(
        NO_FLOOR,
        "With this picture: check that it shows the whole person from head to feet; if the legs are cut off, type "
        "the height. Next time, tilt the camera down a little so that some floor shows in front of the feet.",
        ("image", "body-fit")),
    "several_people": Flag(
        "more than one person-sized object; one was picked",
        "Check that the outlined person is the one to measure; if not, click on the right person in the depth "
        "picture.",
        ("image",)),
    "beyond_working_range": Flag(
        "the subject is closer or farther than the camera's documented working range",
        "Move the person (or the camera) to the camera's working distance, given in the detail, and take the "
        "picture again.",
        ("image",)),
    "out_of_training_range": Flag(
        "a measure lies outside the range the model was trained on",
        "The person or the picture is unlike those the model learned from; treat the answer with caution and check "
        "it against a height-and-weight formula below.",
        ("regression",)),
    "view_disagrees": Flag(
        "the stated view differs from the estimated one by more than 30°",
        "The view typed does not match the picture: check the azimuth and elevation you typed, or leave them empty "
        "so that they are estimated.",
        ("image",)),
    "uncertain_view": Flag(
        "the camera may be in front of or behind the subject (azimuth uncertain)",
        "Type the azimuth if you know it (0 when the person faces the camera), or ask the person to face the "
        "camera squarely and take the picture again.",
        ("regression",)),
    "model_mismatch": Flag(
        "the model was fitted for another camera, distance or view",
        "The model was made for another camera or distance; use the camera and distance it was made for, or the "
        "default model.",
        ("regression",)),
    "camera_assumed": Flag(
        "no camera was given; the preset of the image's size was assumed",
        "Choose the camera that took the picture (or upload its intrinsics JSON) if it is not the one named.",
        ("image",)),
    "interval_unsure": Flag(
        "the model's calibration has too few subjects to promise the interval's level",
        "The range given may be too narrow; report it as approximate.",
        ("regression",)),
    "mixed_pixels": Flag(
        "many returns at the subject's outline lay between two surfaces; the area may be off",
        "Stand the person well in front of a plain wall, or turn on the camera's flying-pixel filter, and take the "
        "picture again.",
        ("image",)),
    "not_a_person": Flag(
        "the object's silhouette is not a standing person's (a board, a post, a wall?)",
        "Check the outline in the depth picture: it may be an object, not the person; click on the person, or "
        "clear the space around them and take the picture again.",
        ("image",)),
    "feet_unsure": Flag(
        "the subject stands farther than this camera tells the feet from the floor; the area near the soles may be "
        "off",
        "Bring the person (or the camera) closer, within the distance given in the detail, and take the picture "
        "again.",
        ("image",)),
    "methods_disagree": Flag(
        "the regression's and the body fit's intervals do not overlap (method both)",
        "The two methods do not agree: check the outline, the clothes and the posture (standing, arms slightly "
        "away from the body), and take the picture again.",
        ("both",)),
    "body_fit_failed": Flag(
        "with method both, the body fit could not serve this image; the regression's answer stands",
        "The body fit could not measure this picture (the detail says why); the regression's answer is shown. Fix "
        "what the detail names to get both.",
        ("both",)),
    "no_interval": Flag(
        "the body fit has no calibrated interval; its bounds are the estimate",
        "The body fit gives no range here; use the regression's range, or report the value as approximate.",
        ("body-fit",)),
    "not_converged": Flag(
        "the fit used all its steps without settling; the body may be off",
        "The body fit did not settle: take the picture again with the person standing still, arms slightly away "
        "from the body.",
        ("body-fit",), internal=True),
    "time_budget": Flag(
        "the fit reached its wall-clock safety stop and returned its best body so far",
        "The body fit ran out of time; its body may be off. Take the picture again, or use the regression.",
        ("body-fit",)),
    "posture_at_limit": Flag(
        "a joint angle sits at the edge of the standing postures the fit allows",
        "Ask the person to stand upright, feet slightly apart, arms slightly away from the body, and take the "
        "picture again.",
        ("body-fit",), internal=True),
    "outside_model_range": Flag(
        "a body parameter sits at the edge of anny's range: the person may be outside the model",
        "The person's shape is at the edge of what the body model can take; treat the body fit's answer with "
        "caution and compare it with the regression.",
        ("body-fit",), internal=True),
    "poor_fit": Flag(
        "the fitted surface leaves many observed points unexplained (not a standing person, clothes, occlusion or "
        "a body outside the model)",
        "The fitted body explains the picture poorly (clothes, something in front of the person, or not a person): "
        "check the outline and take the picture again.",
        ("body-fit",), internal=True),
    "steep_view": Flag(
        "the camera looks at the body from more than 45° above or below",
        "Put the camera at about chest height, level, and take the picture again.",
        ("body-fit",)),
    "feet_not_seen": Flag(
        "the subject's feet are not seen (cut off by the frame or hidden); the stated stature was used",
        "The feet are not in the picture, so the height typed was used: step the person back, or turn the camera "
        "down, so that the whole body and the floor under the feet show, and take the picture again.",
        ("image",)),
    "stature_disagrees": Flag(
        "the stated stature and the one measured on the image differ by more than 5 cm; the stated one was used",
        "Check the height typed (in cm) and that the whole person stands straight in the picture.",
        ("image",)),
    "clothes_unstated": Flag(
        CLOTHES_UNSTATED,
        "Say what the person wears (underwear, a thin gown, light clothes or street clothes): clothes make the "
        "answer read high.",
        ("image",)),
}
#: Flag name -> its meaning (``wbsa.estimation.FLAGS``).
FLAGS: dict[str, str] = {name: flag.meaning for name, flag in FLAG_RECORDS.items()}

#: What the page advises for a flag it does not know.
DEFAULT_ADVICE = "Check the picture and take it again if in doubt."


def terminal_text(name: str, detail: str) -> str:
    """What the terminal says of a flag (``warning: name: <this>``): the raiser's detail (its numbers, the fix in
    command-line words: :func:`wbsa.errors.command_text`), or, for a flag whose detail is the fit's internals (:attr:`Flag.internal`), its meaning
    and what to do, as the page says them; the detail stays in ``--json``.

    Parameters
    ----------
    name : str
        The flag's name (a key of :data:`FLAG_RECORDS`).
    detail : str
        The estimate's detail of it.

    >>> terminal_text("poor_fit", "residual 46.5 mm, 61 % of points within 3 cm").startswith("the fitted surface")
    True
    """
    from wbsa.errors import command_text

    record = FLAG_RECORDS.get(name)
    if record is None or not record.internal:
        return command_text(detail)
    return f"{command_text(record.meaning)}. {record.advice}"
