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
    assert scene.floor is not None and scene.frame == Frame(top=28, bottom=475, left=21, right=611)
    found = sorted(scene.people, key=lambda c: c.bbox_px[0])
    assert len(found) == 5
    for person, (box, feet) in zip(found, FIVE_PEOPLE_BOXES):
        assert _box_error_px(person.bbox_px, box) <= 15, (person.bbox_px, box)
        assert 1.6 < person.top_m < 1.85  # adults' heads over the floor
        assert (person.bottom_m < 0.15) == feet  # the floor contact seen, or the legs cut by the frame


def test_every_person_is_picked_by_a_pixel_on_them_or_within_five_pixels(five_people):
    from wbsa.estimation.subject.people import choose

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
    ((260, 150), r"not a person \(.*6\.\d m away"),  # the corridor's far end, 6 m away
    ((590, 400), r"not a person \(.*flat"),  # the cabinet by the right wall
    ((262, 420), r"no person at pick pixel \(262, 420\) or within 5 pixels"),  # the floor between people
    ((5, 5), r"no person at pick pixel"),  # the band without returns
])
def test_a_pick_on_no_person_is_refused_in_one_line(five_people, pixel, message):
    from wbsa.estimation.subject.people import choose

    _, _, scene = five_people
    with pytest.raises(WbsaError, match=message) as err:
        choose(scene.people, scene.clusters, pixel, scene.image_label, scene.limits)
    assert "\n" not in str(err.value) and "people found: " in str(err.value)
