"""The camera record table: one record per preset, read by the intrinsics, the training sensor, every --help
and the docs."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from wbsa.errors import WbsaError

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_every_help_lists_every_preset(capsys):
    from wbsa.camera.presets import CAMERAS
    from wbsa.cli import main

    for command in (["view"], ["scan"], ["estimate"], ["train"]):
        try:
            main([*command, "--help"])
        except SystemExit:
            pass
        text = " ".join(capsys.readouterr().out.split())
        missing = [name for name in CAMERAS if name not in text]
        assert not missing, (command, missing)


def test_the_docs_preset_table_is_the_camera_table():
    """docs/camera.md's table of presets lists each record's size and working range."""
    from wbsa.camera.presets import CAMERAS

    rows = {m.group(1): m.group(0) for m in re.finditer(r"^\| `([a-z0-9-]+)`[^|]*\| \d+×\d+ .*$", (DOCS / "camera.md").read_text(),
                                                        re.M)}
    assert set(rows) == set(CAMERAS)
    for name, record in CAMERAS.items():
        k = record.intrinsics
        assert f"{k.width}×{k.height}" in rows[name]
        lo, hi = record.working_range_m
        assert re.search(rf"\b{lo:g}(\.0)?–{hi:g}(\.0)? m", rows[name]), (name, rows[name])


def test_the_training_sensor_reads_the_record():
    """Each camera gets its own technology's noise model; a structured-light or stereo camera's depth is
    quantised in disparity with its own baseline and step; time of flight is not. Kinect v1's noise for every
    camera stays a choice."""
    from wbsa.camera.presets import CAMERAS
    from wbsa.training.capture import CaptureSettings, sensor_for

    settings = CaptureSettings()
    for name in ("kinect-v1", "realsense-d455", "kinect-v2"):
        record = CAMERAS[name]
        sensor = sensor_for(record, np.random.default_rng(0), settings)
        assert sensor.noise == "camera" and sensor.technology == record.technology
        assert sensor_for(record, np.random.default_rng(0), CaptureSettings(noise_model="nguyen2012")).noise == "nguyen2012"
        if record.disparity is None:
            assert not sensor.quantise
        else:
            assert sensor.quantise and (sensor.baseline_m, sensor.disparity_step_px) == record.disparity


def test_a_subject_beyond_the_working_range_is_flagged():
    from wbsa.camera.presets import CAMERAS
    from wbsa.estimation.subject.checks import working_range_flags

    for record in CAMERAS.values():
        lo, hi = record.working_range_m
        assert working_range_flags((lo + hi) / 2, record) == {}
        assert "beyond_working_range" in working_range_flags(hi + 0.1, record)
        assert "beyond_working_range" in working_range_flags(lo - 0.05, record)


def test_an_unknown_preset_is_one_line_naming_them():
    from wbsa.camera.presets import CAMERAS, camera_record

    with pytest.raises(WbsaError, match="unknown camera preset 'kinect-v3'; use one of " + ", ".join(CAMERAS)):
        camera_record("kinect-v3")


def test_frames_beyond_where_a_camera_tells_the_feet_from_the_floor_are_flagged():
    """The phone LiDAR's segmentation keeps the feet apart from the floor within 3 m only (bench_estimate.py,
    segmentation by camera and band): its farther frames are flagged, other cameras' are not."""
    from wbsa.camera.intrinsics import Intrinsics
    from wbsa.camera.presets import CAMERAS, resolve_record
    from wbsa.estimation.subject.checks import feet_flags

    lidar = CAMERAS["phone-lidar"]
    assert feet_flags(2.9, lidar) == {} and "step closer" in feet_flags(3.4, lidar)["feet_unsure"]
    assert all(feet_flags(r.working_range_m[1], r) == {} for n, r in CAMERAS.items() if n != "phone-lidar")
    custom = resolve_record(Intrinsics(256, 192, 209.2, 209.2, 124.2, 96.4, name="phone-lidar", max_range_m=9.0))
    assert custom.technology is None  # a user's own calibration is not the preset's record
    assert feet_flags(4.0, custom) == {}
