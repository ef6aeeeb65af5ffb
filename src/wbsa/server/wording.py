"""The page's words for the library's messages: one table from command-line words to what to do on the page.

wbsa's errors and flag details are written for the terminal (``give --azimuth``, ``--camera PRESET``,
``--mask-out``, a PIL mode such as ``is a L image``, anny's parameter names such as ``p_weight = 1.00``); the
command line keeps them. The page shows every error and every flag detail through :func:`page_words`, which
rewrites those words with :data:`PAGE_WORDS` (the one place they are mapped; a test checks that no command-line
word reaches the page). What to do about a flag comes from the flag's record, not from here.
"""

from __future__ import annotations

import re

#: Command-line words (a regular expression) -> the page's words, applied in order to every message the page shows.
PAGE_WORDS: tuple[tuple[str, str], ...] = (
    # several people, and a click that missed them (segmentation)
    (r"; choose one with pick nearest, largest, center or x,y", ": click on the person to measure in the depth "
                                                                "picture"),
    (r"pick pixel \((\d+), (\d+)\)", r"the point clicked (\1, \2)"),
    (r"; pick a pixel on one\b", ": click on one of them"),
    (r"give x,y of a pixel on the subject", "click on the person in the depth picture"),
    (r"\bat pixel \((\d+), (\d+)\)", r"at (\1, \2) in the picture"),
    # the camera
    (r"\(--camera PRESET or an intrinsics JSON\)", "(choose it under Camera, or add its intrinsics file)"),
    (r"give --camera PRESET or an intrinsics JSON", "choose the camera under Camera, or add its intrinsics file"),
    (r"no --camera given", "no camera was chosen"),
    # the view, the method, the clothes, the level
    (r"give --azimuth if you know it", "type the azimuth if you know it"),
    (r"\(--clothing-cm > 0\)", "(clothes other than none)"),
    (r"use --method regression", "choose the method regression"),
    (r"give --level [0-9.]+ or ", ""),
    (r"; on the command line --clothing-cm 1\)", ")"),
    (r"state none \(--clothing-cm 0\)", "choose no clothes"),
    (r"--help lists them\) or an Open3D intrinsics JSON file", "the Camera list shows them) or add its intrinsics file"),
    (r"state them with --clothing-cm", "choose them under Clothes"),
    (r"state them \(--clothes [^)]*\)", "choose them under Clothes"),
    (r"\(--stature-cm, stature_m\)", "(type the height in cm under Height)"),
    (r" \(on the command line --stature-cm \d+\)", ""),
    (r"--stature-cm", "the height field"),
    # the picture and the segmentation
    (r"check the segmentation \(--mask-out\) and pick the subject",
     "check the white outline in the depth picture and click on the person"),
    (r"--mask-out", "the mask download"),
    # image files: PIL's modes in words
    (r"is a (?:L|LA|P|PA|1) image, not a single-channel 16-bit depth image",
     "is an ordinary grey or colour picture, not a depth image"),
    (r"is a (?:RGB|RGBA|RGBX|CMYK|YCbCr|HSV|LAB) image, not a single-channel 16-bit depth image",
     "is a colour picture, not a depth image"),
    (r"is a [A-Za-z0-9;]+ image, not a single-channel 16-bit depth image", "is not a depth image"),
    (r"save depth as 16-bit PNG in millimetres", "export the depth frame from the camera's software as a 16-bit PNG "
                                                "in millimetres"),
    (r"is a [A-Za-z0-9;]+ TIFF, not single-channel depth", "is a TIFF picture, not a depth image"),
    # the body model's parameters (anny's names)
    (r"\bp_(age|muscle|weight|height|proportions) = (0\.0\d)", r"\1 at the body model's lowest"),
    (r"\bp_(age|muscle|weight|height|proportions) = (0\.9\d|1\.00)", r"\1 at the body model's highest"),
    (r"\bl_(\w+?) = -\d\.\d\d", r"\1 at the body model's least"),
    (r"\bl_(\w+?) = \+\d\.\d\d", r"\1 at the body model's most"),
)

_COMPILED = tuple((re.compile(pattern), words) for pattern, words in PAGE_WORDS)
#: Words in a message that say the operator should click a person in the depth picture.
CHOOSE_PERSON = ("click on the person to measure", "click on one of them", "click on the person in the depth picture")


def page_words(text: str) -> str:
    """``text`` with the command line's words replaced by the page's (:data:`PAGE_WORDS`).

    >>> page_words("azimuth 160° ± 40°; give --azimuth if you know it")
    'azimuth 160° ± 40°; type the azimuth if you know it'
    """
    for pattern, words in _COMPILED:
        text = pattern.sub(words, text)
    return text


def choose_person(text: str) -> bool:
    """Whether a page message (after :func:`page_words`) asks for a click on a person."""
    return any(words in text for words in CHOOSE_PERSON)
