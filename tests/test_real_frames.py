"""A real frame (PCL's five_people.pcd, tests/fixtures/pcl): every person found and selectable, a pick on
anything else refused in one line."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.frames import FIVE_PEOPLE_BOXES, pcd_depth
from wbsa.errors import WbsaError


@pytest.fixture(scope="module")
def five_people():
    """The frame's depth, its camera (the tum preset: its points fit fx = 525, c = (319.5, 239.5)) and its
    people (:func:`wbsa.estimation.subject.segment.find_people`)."""
    from wbsa.camera.presets import resolve_camera
    from wbsa.estimation.subject.segment import find_people

    depth, camera = pcd_depth(), resolve_camera("tum")
    return depth, camera, find_people(depth, camera)


def _box_error_px(a, b) -> int:
    return max(abs(int(u) - int(v)) for u, v in zip(a, b))


def test_the_five_people_are_found_apart_with_their_boxes(five_people):
    """Five people, two of them one object in 3-D (an arm on an arm), each found within 15 pixels of the box
    read off the image by eye; the frame's bands without returns are its border, so the floor is found."""
    from wbsa.estimation.subject.frame import Frame

    _, _, scene = five_people
    assert scene.floor is not None and scene.frame == Frame(top=27, bottom=476, left=20, right=612)
    found = sorted(scene.people, key=lambda c: c.bbox_px[0])
    assert len(found) == 5
    for person, (box, feet) in zip(found, FIVE_PEOPLE_BOXES):
        assert _box_error_px(person.bbox_px, box) <= 15, (person.bbox_px, box)
        assert 1.6 < person.top_m < 1.85  # adults' heads over the floor
        assert (person.bottom_m < 0.15) == feet  # the floor contact seen, or the legs cut by the frame


def test_every_person_is_picked_by_a_pixel_on_them_or_within_five_pixels(five_people):
    from wbsa.estimation.subject.pick import choose

    _, _, scene = five_people
    picked = set()
    for box, _ in FIVE_PEOPLE_BOXES:
        x, y = (box[0] + box[2]) // 2, box[1] + (box[3] - box[1]) // 3  # the chest
        person = choose(scene.people, scene.clusters, (x, y), scene.image_label, scene.limits)
        assert _box_error_px(person.bbox_px, box) <= 15 and person.label not in picked
        picked.add(person.label)
    # a pixel without a return 3 pixels left of the first person's outline, at her chest's row
    row = FIVE_PEOPLE_BOXES[0][0][1] + 150
    first = np.flatnonzero(scene.image_label[row] == choose(scene.people, scene.clusters, (86, 270),
                                                            scene.image_label, scene.limits).label)[0]
    assert scene.image_label[row, first - 3] < 0
    near = choose(scene.people, scene.clusters, (int(first) - 3, row), scene.image_label, scene.limits)
    assert _box_error_px(near.bbox_px, FIVE_PEOPLE_BOXES[0][0]) <= 15


@pytest.mark.parametrize("pixel, message", [
    # the corridor's far end, 6 m away
    ((260, 150), r"pick pixel \(260, 150\) lies on an object that is not a person \(.*6\.\d m away"),
    ((590, 400), r"not a person \(.*flat"),  # the cabinet by the right wall
    ((262, 420), r"no person at pick pixel \(262, 420\) or within 5 pixels"),  # the floor between people
    ((5, 5), r"no person at pick pixel"),  # the band without returns
])
def test_a_pick_on_no_person_is_refused_in_one_line(five_people, pixel, message):
    from wbsa.estimation.subject.pick import choose

    _, _, scene = five_people
    with pytest.raises(WbsaError, match=message) as err:
        choose(scene.people, scene.clusters, pixel, scene.image_label, scene.limits)
    assert "\n" not in str(err.value) and "people found: " in str(err.value)


# ------------------------------------------------- the estimate on the real frame and on renders of its cases
def test_the_person_cut_at_the_knees_is_refused_and_answered_with_a_stature(five_people, tmp_path):
    """The nearest person of the real frame (dark shirt, 2 m) is cut by the frame at the knees: refused in one
    line (exit 2); with a stated stature, answered at that stature and flagged ``feet_not_seen``. The ``.pcd``
    itself is read, its camera recovered from its points; its depth saved as ``.npy`` is read with ``--camera``
    (a pick on no person is refused in its words by the test above, on the same people)."""
    from helpers.cli import assert_one_line_error, run_cli
    from helpers.frames import FIVE_PEOPLE

    import json

    depth, _, _ = five_people
    path = tmp_path / "five_people.npy"
    np.save(path, depth)
    base = ["estimate", FIVE_PEOPLE, "--pick", "530,250"]
    assert_one_line_error(*run_cli(*base)[::2], "feet not seen", "--stature-cm")
    code, out, err = run_cli(*base, "--stature-cm", "180", "--json")
    est = json.loads(out)
    assert code == 0 and est["stature_m"] == 1.8 and est["stature_stated_m"] == 1.8
    assert "feet_not_seen" in est["flags"] and "clothes_unstated" in est["flags"] and not est["clothing_stated"]
    assert est["wbsa_lo_m2"] < est["wbsa_m2"] < est["wbsa_hi_m2"] and est["wbsa_m2"] > 1.6  # an adult's, not a child's
    assert est["camera"] == "tum" and "camera_assumed" not in est["flags"]  # the preset its grid matches
    code, out, err = run_cli("estimate", path, "--camera", "tum", "--pick", "530,250", "--stature-cm", "180", "--json")
    assert code == 0 and json.loads(out)["wbsa_m2"] == est["wbsa_m2"]  # the same frame, the same camera
    assert_one_line_error(*run_cli(*base, "--clothes", "coat")[::2], "--clothes", "coat")
    assert_one_line_error(*run_cli(*base, "--clothes", "light", "--clothing-cm", "1")[::2], "not both")


def test_a_640x480_frame_without_a_camera_is_refused_naming_the_cameras_of_that_size(tmp_path):
    """A 640 x 480 depth image (the size of Kinect v1 and of TUM's calibration, focal lengths 576 and 525 px)
    without a camera is refused in one line naming both and the word to add, on the command line (exit 2) and in
    Python (``code="camera_size"``), before any person is looked for (an empty frame: the size alone decides);
    the real frame's organised ``.pcd`` brings its own camera and is answered (the test above)."""
    from helpers.cli import assert_one_line_error, run_cli
    import wbsa

    path = tmp_path / "frame.npy"
    np.save(path, np.zeros((480, 640)))
    assert_one_line_error(*run_cli("estimate", path, "--pick", "86,250")[::2],
                          "640x480 pixels fits 2 cameras of different focal lengths (kinect-v1 576 px, tum 525 px)",
                          "add --camera kinect-v1 or --camera tum", "intrinsics JSON file")
    with pytest.raises(WbsaError, match=r"camera='kinect-v1' in Python") as err:
        wbsa.estimate(path, "auto")
    assert err.value.code == "camera_size" and err.value.field == "camera"
    assert "choose the camera under Camera" in err.value.page_words()


@pytest.fixture(scope="module")
def side_by_side(body_model):
    """Two people side by side in a room (:func:`wbsa.testing.frames.side_by_side`): the depth, the man's
    pixels, both people's."""
    from wbsa.testing.frames import side_by_side as render

    return render(body_model)


def _pick(truth) -> tuple[int, int]:
    ys, xs = np.nonzero(truth)
    return int(np.median(xs)), int(np.median(ys))


def test_a_render_cut_at_the_knees_is_refused_unless_its_stature_is_stated(side_by_side):
    """The render's rows below the man's knees blanked (a frame cut there): refused, not read as a child;
    stated, his stature is used and the legs below the cut are completed from the population's proportions:
    the answer stays within 8 % of the whole frame's, its interval wider. Alone (the room blanked: the legs
    end over nothing, no floor), the cut is told by the legs' shape and refused the same way."""
    import wbsa
    from wbsa.estimation import SegmentSettings

    depth, man, _ = side_by_side
    rows = np.flatnonzero(man.any(axis=1))
    cut = depth.copy()
    cut[int(rows[-1] - 0.27 * (rows[-1] - rows[0])):] = 0.0  # the knees: 27 % of the stature up
    settings = SegmentSettings(pick=_pick(man))
    whole = wbsa.estimate(depth, "kinect-v2", segment=settings)
    assert "feet_not_seen" not in whole.flags and 1.8 < whole.stature_m < 1.95
    with pytest.raises(WbsaError, match=r"feet not seen: the feet touch the bottom edge of the picture") as err:
        wbsa.estimate(cut, "kinect-v2", segment=settings)
    assert "\n" not in str(err.value)
    stated = wbsa.estimate(cut, "kinect-v2", segment=settings, stature_m=whole.stature_m)
    assert "feet_not_seen" in stated.flags and stated.stature_m == whole.stature_m
    assert "% of its area) is not seen" in stated.flags["feet_not_seen"]
    assert abs(stated.wbsa_m2 / whole.wbsa_m2 - 1) < 0.08
    assert stated.wbsa_hi_m2 - stated.wbsa_lo_m2 > whole.wbsa_hi_m2 - whole.wbsa_lo_m2
    alone = np.where(man, cut, 0.0)
    with pytest.raises(WbsaError, match=r"feet not seen: its lowest part is no wider or deeper than the legs"):
        wbsa.estimate(alone, "kinect-v2")
    assert "feet_not_seen" in wbsa.estimate(alone, "kinect-v2", stature_m=whole.stature_m).flags
    with pytest.raises(WbsaError, match=r"stated stature .* must be a height of 0.5 to 2.5 m"):
        wbsa.estimate(cut, "kinect-v2", segment=settings, stature_m=18.0)


def test_only_legs_nobody_or_a_pick_on_no_person_is_one_line(side_by_side):
    from wbsa.estimation.subject.segment import SegmentSettings, segment_subject
    from wbsa.camera import preset

    depth, man, everyone = side_by_side
    camera = preset("kinect-v2")
    rows = np.flatnonzero(man.any(axis=1))
    legs = depth.copy()
    legs[:int(rows[-1] - 0.45 * (rows[-1] - rows[0]))] = 0.0  # the frame's top at the hips
    with pytest.raises(WbsaError, match=r"no person in the depth image.*the top of the frame cuts it off"):
        segment_subject(legs, camera, SegmentSettings(pick="nearest"))
    nobody = np.where(everyone, 0.0, depth)
    with pytest.raises(WbsaError, match=r"no person in the depth image|holds only floor and walls"):
        segment_subject(nobody, camera, SegmentSettings(pick="nearest"))
    with pytest.raises(WbsaError, match=r"no person at pick pixel \(40, 100\) or within 5 pixels"):
        segment_subject(depth, camera, SegmentSettings(pick=(40, 100)))
    for truth in (man, everyone & ~man):  # each picked by a pixel on them
        seg = segment_subject(depth, camera, SegmentSettings(pick=_pick(truth)))
        assert (seg.mask & truth).sum() > 0.97 * truth.sum() and len(seg.others) == 1


def test_named_clothes_widen_the_interval_and_unstated_clothes_are_flagged(side_by_side):
    """A named layer predicts as its thickness stated explicitly, with an interval wider on each side by the
    change of the estimate over the layer's uncertainty; nothing stated answers as 0 cm, flagged, and the
    FHIR method says so."""
    import wbsa
    from wbsa.estimation import SegmentSettings
    from wbsa.estimation.clothes import CLOTHES
    from wbsa.estimation.fhir import fhir_observation

    depth, man, _ = side_by_side
    kw = dict(segment=SegmentSettings(pick=_pick(man)))
    light = CLOTHES["light"]
    named = wbsa.estimate(depth, "kinect-v2", clothes="light", **kw)
    explicit = wbsa.estimate(depth, "kinect-v2", clothing_m=light.layer_m, **kw)
    thicker = wbsa.estimate(depth, "kinect-v2", clothing_m=light.layer_m + light.sd_m, **kw)
    delta = explicit.wbsa_m2 - thicker.wbsa_m2
    assert named.wbsa_m2 == explicit.wbsa_m2 and delta > 0.01
    assert named.wbsa_lo_m2 == pytest.approx(explicit.wbsa_lo_m2 - delta, abs=1e-12)
    assert named.wbsa_hi_m2 == pytest.approx(explicit.wbsa_hi_m2 + delta, abs=1e-12)
    unstated = wbsa.estimate(depth, "kinect-v2", **kw)
    zero = wbsa.estimate(depth, "kinect-v2", clothing_m=0.0, **kw)
    assert (unstated.wbsa_m2, unstated.wbsa_lo_m2, unstated.wbsa_hi_m2) == (zero.wbsa_m2, zero.wbsa_lo_m2,
                                                                            zero.wbsa_hi_m2)
    assert "clothes_unstated" in unstated.flags and "clothes_unstated" not in zero.flags
    said = unstated.flags["clothes_unstated"]  # in Python, the argument; on the terminal, the option
    assert "state them (clothes='underwear', 'thin-gown', 'light' or 'street')" in said and "--clothes" not in said
    assert unstated.to_dict()["clothing_stated"] is False and named.to_dict()["clothes"] == "light"
    assert "clothes not stated" in fhir_observation(unstated)["method"]["text"]
    assert "clothes stated: light clothes" in fhir_observation(named)["method"]["text"]
    assert "0.0 cm layer" in fhir_observation(zero)["method"]["text"]
    for bad, message in ((dict(clothes="coat"), "unknown clothes 'coat'"),
                         (dict(clothes="light", clothing_m=0.01), "not both")):
        with pytest.raises(WbsaError, match=message):
            wbsa.estimate(depth, "kinect-v2", **bad, **kw)


def test_the_frame_moves_in_past_bands_without_returns_but_not_past_a_head_or_a_body_alone():
    """A band without returns along an edge, next to rows seen across, is the frame's edge (a registered
    camera's band, a blanked bottom); the empty space over a wall with a head in it, or around a body alone
    in the image, is not."""
    from wbsa.estimation.subject.frame import Frame, image_frame

    room = np.zeros((100, 200), dtype=bool)
    room[30:, :] = True  # a wall and floor under an empty top
    assert image_frame(room) == Frame(30, 99, 0, 199)
    blanked = room.copy()
    blanked[80:] = False  # the bottom blanked
    assert image_frame(blanked) == Frame(30, 79, 0, 199)
    head = room.copy()
    head[18:30, 95:105] = True  # a head 12 rows over the wall's top
    assert image_frame(head).top == 0
    alone = np.zeros((100, 200), dtype=bool)
    alone[10:90, 90:110] = True  # a body alone: narrow rows, empty around
    assert image_frame(alone) == Frame(0, 99, 0, 199)


# ------------------------------------------------------------------------------------- point clouds as input
def test_an_organised_pcd_brings_its_own_camera():
    """PCL's frame: the camera recovered from its own points is TUM's Kinect v1 (fx = fy = 525, c = (319.5,
    239.5)) to well within 0.5 % of the focal length, so the tum preset is taken; its depth is the points' z in
    grid order."""
    from helpers.frames import FIVE_PEOPLE
    from wbsa.core.point_cloud import grid_intrinsics, point_cloud_depth, read_point_cloud

    depth, preset_taken = point_cloud_depth(FIVE_PEOPLE)
    assert preset_taken.name == "tum"
    camera = grid_intrinsics(read_point_cloud(FIVE_PEOPLE).points_m.reshape(480, 640, 3))
    assert (camera.width, camera.height) == (640, 480)
    assert abs(camera.fx / 525.0 - 1) < 0.005 and abs(camera.fy / 525.0 - 1) < 0.005
    assert abs(camera.cx - 319.5) < 0.5 and abs(camera.cy - 239.5) < 0.5
    z = read_point_cloud(FIVE_PEOPLE).points_m[:, 2].reshape(480, 640)
    assert np.array_equal(depth, np.where(np.isfinite(z), z, 0.0)) and 0.7 < (depth > 0).mean() < 0.85


def test_a_pcd_written_from_a_render_gives_back_its_camera_and_its_estimate(side_by_side, tmp_path):
    """A render of known intrinsics (Kinect v2) written as an organised PCD: the camera comes back within
    0.5 % of its focal length and half a pixel of its centre, and the estimate from the file without a camera
    is the estimate of the depth image (as float32) with the camera named; a stated camera the grid contradicts
    is refused."""
    from helpers.cli import assert_one_line_error, run_cli
    from helpers.frames import grid_points, write_organised_pcd
    import wbsa
    from wbsa.camera import preset
    from wbsa.estimation import SegmentSettings

    depth, man, _ = side_by_side
    truth = preset("kinect-v2")
    path = write_organised_pcd(tmp_path / "render.pcd", grid_points(depth, truth))
    from wbsa.core.point_cloud import grid_intrinsics, point_cloud_depth, read_point_cloud

    read, taken = point_cloud_depth(path)
    camera = grid_intrinsics(read_point_cloud(path).points_m.reshape(*depth.shape, 3))
    assert taken.name == "kinect-v2" and abs(camera.fx / truth.fx - 1) < 0.005 and abs(camera.fy / truth.fy - 1) < 0.005
    assert abs(camera.cx - truth.cx) < 0.5 and abs(camera.cy - truth.cy) < 0.5
    assert np.allclose(read, depth, rtol=1e-6, atol=0)
    assert (camera.fx, camera.fy, camera.cx, camera.cy) == (truth.fx, truth.fy, truth.cx, truth.cy)  # to 0.001 px
    pick = _pick(man)
    stored = depth.astype(np.float32).astype(np.float64)  # the depth as the file's float32 points hold it
    named = wbsa.estimate(stored, "kinect-v2", segment=SegmentSettings(pick=pick))
    own = wbsa.estimate(path, "auto", segment=SegmentSettings(pick=pick))
    assert own.wbsa_m2 == named.wbsa_m2 and "camera_assumed" not in own.flags
    assert own.camera == "kinect-v2"  # the preset the grid matches, with its sensor model
    assert wbsa.estimate(path, "kinect-v2", segment=SegmentSettings(pick=pick)).camera == "kinect-v2"
    assert_one_line_error(*run_cli("estimate", path, "--camera", "kinect-v1")[::2], "render.pcd's points lie on the grid",
                          "fx 365.5", "leave out --camera")


def test_a_ply_is_projected_through_the_stated_camera_or_refused_without_one(side_by_side, tmp_path):
    """A ``.ply`` of the render's points has no grid: without ``--camera`` it is refused in one line naming
    the option; with it, its points project back onto the render's depth image, and the estimate is the
    depth image's."""
    import open3d as o3d

    from helpers.cli import assert_one_line_error, run_cli
    from helpers.frames import grid_points
    import wbsa
    from wbsa.camera import preset
    from wbsa.core.point_cloud import project_points
    from wbsa.estimation import SegmentSettings

    depth, man, _ = side_by_side
    camera = preset("kinect-v2")
    points = grid_points(depth, camera).reshape(-1, 3)
    points = points[np.isfinite(points).all(axis=1)]
    assert np.allclose(project_points(points, camera), depth, rtol=1e-9, atol=0)  # the round trip
    path = tmp_path / "render.ply"
    o3d.io.write_point_cloud(str(path), o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points)))
    assert_one_line_error(*run_cli("estimate", path)[::2], "render.ply is a .ply point cloud, without a pixel grid",
                          "--camera")
    pick = _pick(man)
    named = wbsa.estimate(depth, "kinect-v2", segment=SegmentSettings(pick=pick))
    code, out, err = run_cli("estimate", path, "--camera", "kinect-v2", "--pick", f"{pick[0]},{pick[1]}", "--json")
    import json

    assert code == 0, err
    assert json.loads(out)["wbsa_m2"] == pytest.approx(named.wbsa_m2, rel=1e-4)


def test_a_point_cloud_that_cannot_be_read_is_refused_in_one_line(tmp_path):
    """Not a PCD, an empty PLY, a point in absurd units, a depth scale that is no scale: one line each, the
    problem named."""
    from helpers.cli import assert_one_line_error, run_cli

    (tmp_path / "text.pcd").write_text("hello\n")
    (tmp_path / "empty.ply").write_bytes(b"")
    (tmp_path / "far.ply").write_text("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                      "property float z\nend_header\n1e30 1e30 1e-30\n")
    assert_one_line_error(*run_cli("estimate", tmp_path / "text.pcd")[::2], "text.pcd has no PCD header")
    assert_one_line_error(*run_cli("estimate", tmp_path / "empty.ply", "--camera", "kinect-v2")[::2],
                          "empty.ply is empty (0 bytes)")
    code, _, err = run_cli("estimate", tmp_path / "far.ply", "--camera", "kinect-v2")
    assert_one_line_error(code, err, "none of the 1 points falls in the kinect-v2 camera's image")
    from wbsa.core.point_cloud import read_point_cloud

    with pytest.raises(WbsaError, match="must be a positive number of coordinate units per metre"):
        read_point_cloud(tmp_path / "far.ply", units_per_m=0)
