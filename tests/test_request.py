"""The one front door of an estimate: the request built once, the camera travelling as its record."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest

import wbsa
from wbsa.errors import WbsaError

ESTIMATION = Path(__file__).resolve().parents[1] / "src" / "wbsa" / "estimation"
#: What looks a camera up again by name or by equality.
LOOKUPS = re.compile(r"\b(preset_record|camera_record|envelope_model)\(|\bCAMERAS\b")
#: The modules at or above the request, where the camera is still what the user gave: the request itself (it
#: resolves the camera) and the command line (it lists the presets in its help).
ABOVE_THE_REQUEST = {"request.py", "command.py"}


def test_nothing_below_the_request_looks_the_camera_up_again():
    found = [f"{path.relative_to(ESTIMATION)}:{n}: {line.strip()}"
             for path in sorted(ESTIMATION.rglob("*.py")) if path.name not in ABOVE_THE_REQUEST
             for n, line in enumerate(path.read_text().splitlines(), 1) if LOOKUPS.search(line)]
    assert found == [], "the camera's record travels in the request and the Subject:\n" + "\n".join(found)


def test_the_lookup_pattern_sees_a_lookup():
    assert LOOKUPS.search("sensor = envelope_model(intrinsics)") and LOOKUPS.search("record = CAMERAS.get(name)")
    assert not LOOKUPS.search("(:func:`wbsa.sensor.technology.envelope_model`)")


def test_a_preset_gives_its_record_and_its_noise_model():
    from wbsa.camera.presets import CAMERAS
    from wbsa.estimation.request import EstimateRequest
    from wbsa.sensor.technology import camera_model

    request = EstimateRequest.build("kinect-v2")
    assert request.camera is CAMERAS["kinect-v2"] and request.camera.technology == "time-of-flight"
    assert request.sensor == camera_model(CAMERAS["kinect-v2"]) and not request.camera_assumed
    with pytest.raises(dataclasses.FrozenInstanceError):
        request.level = 0.5  # type: ignore[misc]


def test_an_intrinsics_json_gives_a_record_whose_technology_is_unknown(tmp_path):
    from wbsa.camera.presets import CAMERAS
    from wbsa.estimation.request import EstimateRequest
    from wbsa.sensor.technology import camera_model

    k = CAMERAS["kinect-v2"].intrinsics
    path = tmp_path / "mine.json"
    path.write_text(json.dumps({"width": k.width, "height": k.height,
                                "intrinsic_matrix": [k.fx, 0, 0, 0, k.fy, 0, k.cx, k.cy, 1]}))
    request = EstimateRequest.build(str(path))
    assert request.camera.technology is None and request.camera.feet_within_m is None
    assert (request.camera.intrinsics.width, request.camera.intrinsics.fx) == (k.width, k.fx)
    assert request.sensor == camera_model(CAMERAS["kinect-v1"])  # an unknown technology: Kinect v1's noise
    assert EstimateRequest.build(k).camera is CAMERAS["kinect-v2"]  # a preset's intrinsics are that preset


def test_auto_is_resolved_by_the_image_and_the_size_is_checked_once():
    from wbsa.estimation.request import EstimateRequest

    request = EstimateRequest.build("auto")
    assert request.camera is None and request.camera_assumed
    resolved = request.for_image(np.zeros((424, 512)))
    assert resolved.camera.name == "kinect-v2" and resolved.sensor is not None
    with pytest.raises(WbsaError, match="the depth image is 512x100 but camera kinect-v2 is 512x424"):
        resolved.for_image(np.zeros((100, 512)))


def test_the_request_refuses_in_one_line_before_any_image_is_read():
    from wbsa.estimation.request import EstimateRequest

    for kwargs, message in ((dict(level=1.5), "interval level 1.5"), (dict(clothes="parka"), "unknown clothes"),
                            (dict(clothing_m=0.2), "0 to 0.05 m"), (dict(stature_m=3.0), "0.5 to 2.5 m"),
                            (dict(method="magic"), "estimation method 'magic' is unknown")):
        with pytest.raises(WbsaError, match=message):
            EstimateRequest.build("kinect-v2", **kwargs)
    with pytest.raises(WbsaError, match="unknown camera preset 'kinect-v9'"):
        wbsa.estimate("no-such-file.png", "kinect-v9")


def test_clothing_is_the_deprecated_name_of_clothes():
    with pytest.warns(DeprecationWarning, match="use clothes="), pytest.raises(WbsaError, match="unknown clothes 'coat'"):
        wbsa.estimate(np.zeros((424, 512)), "kinect-v2", clothing="coat")
    with pytest.raises(WbsaError, match="unknown clothes 'coat'"):
        wbsa.estimate(np.zeros((424, 512)), "kinect-v2", clothes="coat")
    with pytest.raises(TypeError):
        wbsa.estimate(np.zeros((424, 512)), "kinect-v2", show_progress=False)  # accepted and ignored no more


def test_a_caller_of_estimate_finds_what_it_takes_at_the_top():
    from wbsa.estimation.methods.regression.model import EstimatorModel
    from wbsa.estimation.subject.settings import SegmentSettings

    assert wbsa.EstimatorModel is EstimatorModel and wbsa.SegmentSettings is SegmentSettings


def test_the_limits_are_one_table_read_by_the_command_line_and_the_checks():
    from wbsa.cli import build_parser
    from wbsa.estimation.clothes import check_clothing
    from wbsa.estimation.limits import LIMITS
    from wbsa.estimation.subject.checks import check_stated_stature

    stature, clothing = LIMITS["stature"], LIMITS["clothing"]
    assert check_stated_stature(stature.high) == stature.high
    with pytest.raises(WbsaError, match=f"{stature.low:g} to {stature.high:g} m"):
        check_stated_stature(stature.high + 0.01)
    check_clothing(clothing.high)
    with pytest.raises(WbsaError):
        check_clothing(clothing.high + 0.001)
    parser = build_parser()
    with pytest.raises(SystemExit):
        parser.parse_args(["estimate", "d.png", "--stature-cm", str(100 * stature.high + 1)])
    args = parser.parse_args(["estimate", "d.png", "--stature-cm", str(100 * stature.high)])
    assert args.stature_cm == 100 * stature.high and args.max_depth == LIMITS["depth"].high


def test_no_camera_preset_is_looked_up_below_the_request():
    """The request resolves the camera once (its record, technology and noise model); below it, in
    ``wbsa.estimation``, nothing looks a preset up again by name or by equality."""
    import re
    from pathlib import Path

    import wbsa.estimation

    root = Path(wbsa.estimation.__file__).parent
    lookup = re.compile(r"\b(preset_record|camera_record|envelope_model)\(|\bCAMERAS\b")
    found = [f"{p.relative_to(root)}:{n}" for p in sorted(root.rglob("*.py")) if p.name != "request.py"
             for n, line in enumerate(p.read_text().splitlines(), 1) if lookup.search(line.split("#")[0])]
    assert found == []
