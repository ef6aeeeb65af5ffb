"""``wbsa serve``: the page in a real browser (Debian's headless Chromium), the routes, and every bad input.

The server runs on a free loopback port in a thread of this process; the browser is driven by selenium with
the system's chromedriver. Frames are rendered rooms of known virtual bodies (Kinect v2, as in
tests/test_estimate.py) and every number on the page is compared with :func:`wbsa.estimate` on the same file.
"""

from __future__ import annotations

import io
import json
import re
import socket
import struct
import threading
import urllib.error
import urllib.request
import zlib
from pathlib import Path

import numpy as np
import pytest

from helpers.browser import ARTEFACTS, headless_chromium


# ---------------------------------------------------------------- frames, server, browser
@pytest.fixture(scope="module")
def frames(body_model, tmp_path_factory):
    """Kinect v2 frames (16-bit PNG, mm) of a man alone in a room and of the man with a woman beside him,
    with the pixels of each person."""
    from wbsa.bodies.anthropometry import reference_adult
    from wbsa.camera import MeshScene, View, preset
    from wbsa.core import write_depth_png
    from wbsa.training.room import compose_room
    from wbsa.sensor.settings import SensorSettings
    from wbsa.simulate import simulate_view

    folder = tmp_path_factory.mktemp("frames")
    man = body_model.skin_mesh(body_model.rest_bodies(reference_adult(0.0)).vertices[0])
    woman = body_model.skin_mesh(body_model.rest_bodies(reference_adult(1.0)).vertices[0])
    out = {}
    for name, others in (("one", ()), ("two", ((woman, 1.3),))):
        room = compose_room(man, 20.0, wall_behind_m=0.8, others=others)
        frame = simulate_view(MeshScene(room.mesh, surroundings=True), preset("kinect-v2"), View(20.0, 12.0, 3.2),
                              sensor=SensorSettings(noise="nguyen2012"), seed=4, keep_frame=True,
                              target=room.subject_center).frame
        path = folder / f"{name}.png"
        write_depth_png(path, frame.depth_m)
        tri = frame.triangle_id
        n_man = len(man.faces)
        out[name] = {"path": path, "man": (tri >= 0) & (tri < n_man),
                     "woman": (tri >= n_man) & (tri < n_man + len(woman.faces))}
    return out


@pytest.fixture(scope="module")
def server(small_estimator_model, tmp_path_factory):
    """The app on a free loopback port (upload limit 8 MiB, so the limit is cheap to test; body fits of
    :data:`FIT_STEPS` steps); its temporary folder is checked to be gone after the server stops."""
    from wbsa.server.app import create_app
    from wbsa.server.command import start_in_thread

    app = create_app(small_estimator_model, temp_dir=str(tmp_path_factory.mktemp("serve")),
                     max_upload_bytes=8 * 2**20, max_pending=24, body_fit=_fit_settings())
    url, stop = start_in_thread(app)
    yield url, app
    stop()
    assert not app.state.root.exists()


@pytest.fixture(scope="module")
def browser():
    """Headless Chromium (selenium + the Debian chromedriver) with a fresh profile, closed network features."""
    with headless_chromium(1280, 1900) as driver:
        yield driver


#: Steps of the tests' body fits (two restarts): few, so a fit takes a second or two (the page's behaviour, not the fit's quality).
FIT_STEPS = 30


def _fit_settings():
    from wbsa.estimation.methods.body_fit.settings import BodyFitSettings

    return BodyFitSettings(steps=FIT_STEPS, restarts=2, keep_restarts=1)


def _estimate(path, model, pick=None, **kw):
    import wbsa
    from wbsa.estimation import SegmentSettings

    kw.setdefault("clothes", "underwear")  # what the page's tests choose
    return wbsa.estimate(str(path), "kinect-v2", str(model), segment=SegmentSettings(pick=pick), **kw)


def _wait(driver, script: str, timeout: float = 60):
    """Wait until the JavaScript expression ``script`` is true."""
    from selenium.webdriver.support.ui import WebDriverWait

    WebDriverWait(driver, timeout, poll_frequency=0.1).until(lambda d: d.execute_script(f"return {script}"))


def _upload(driver, url: str, *paths, camera: str = "kinect-v2", height_cm: str = "", mass_kg: str = "",
            method: str = "regression", clothes: str = "underwear"):
    """Open the page, fill the form and choose ``paths`` (the page sends them on choosing; none: only fill it)."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    driver.get(url)
    _wait(driver, "document.getElementById('camera').options.length > 1")
    Select(driver.find_element(By.ID, "camera")).select_by_value(camera)
    driver.find_element(By.ID, "height").send_keys(height_cm)
    driver.find_element(By.ID, "mass").send_keys(mass_kg)
    Select(driver.find_element(By.ID, "method")).select_by_value(method)
    if clothes:
        Select(driver.find_element(By.ID, "clothes")).select_by_value(clothes)
    if paths:
        driver.find_element(By.ID, "depth-file").send_keys("\n".join(str(p) for p in paths))


def _answer(driver) -> dict:
    """The answer the page shows: its id, the WBSA it holds, the error line, the 3-D view's triangles."""
    return driver.execute_script("""
        const v = document.getElementById('wbsa-value');
        return {id: document.body.dataset.answer || '', wbsa: v.dataset.wbsaM2 || '', text: v.textContent,
                error: document.getElementById('error').hidden ? '' : document.getElementById('error').textContent,
                triangles: document.getElementById('viewer').dataset.triangles || '',
                flags: [...document.querySelectorAll('#flag-list li')].map(li => li.textContent),
                flagNames: [...document.querySelectorAll('#flag-list li')].map(li => li.dataset.flag),
                formulae: document.querySelectorAll('#formulae-table tbody tr').length,
                depthWidth: document.getElementById('depth-img').naturalWidth,
                downloads: [...document.querySelectorAll('#downloads a')].map(a => a.getAttribute('href'))};""")


#: Command-line words that must not reach the page (the page says what to do on the page).
COMMAND_LINE_WORDS = re.compile(r"--[a-z]|\bp_[a-z]+ = |\bis an? [A-Z0-9;]+ (image|TIFF)\b|choose one with pick|"
                                r"\bpick pixel\b|PRESET")


def _fitted_at_the_model_edge():
    """The body fit's ``outside_model_range`` detail of a body at its model's edges."""
    import pandas as pd

    from wbsa.estimation.methods.body_fit.fit import model_edge_detail

    parameters = pd.Series({"p_age": 0.0, "p_muscle": 0.5, "p_weight": 1.0, "p_height": 0.5, "p_proportions": 0.5,
                            "l_belly": 1.0, "l_waist": 0.2})
    detail = model_edge_detail(parameters)
    assert str(detail) == "p_age = 0.00, p_weight = 1.00, l_belly = +1.00"
    return detail


def _page_text(driver) -> str:
    """The words the page shows (visible text only)."""
    return driver.execute_script("return document.body.innerText")


def _shown(driver, element_id: str) -> bool:
    """Whether the element is laid out with a size (not hidden, nor inside something hidden)."""
    return driver.execute_script("const r = document.getElementById(arguments[0]).getBoundingClientRect(); "
                                 "return r.width > 0 && r.height > 0", element_id)


def _screenshot(driver, name: str) -> Path:
    """Save the page as ``test-artefacts/<name>`` (PNG) and return its path."""
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    shot = ARTEFACTS / name
    driver.save_screenshot(str(shot))
    print(f"screenshot: {shot}")
    assert shot.stat().st_size > 20_000
    return shot


# ---------------------------------------------------------------- in the browser
def test_the_page_shows_the_answer_of_wbsa_estimate_for_a_rendered_body(server, browser, frames,
                                                                          small_estimator_model):
    """A known body in a room: the page's WBSA, interval and flags are wbsa.estimate's on the same file; the
    depth picture, the 3-D view (every triangle of the surface), the view sketch, the formulae and the
    downloads are shown. A screenshot is kept as a test artefact."""
    from wbsa.estimation.flags import FLAGS

    url, app = server
    # the page states the clothes chosen and the height typed, as the stature
    est = _estimate(frames["one"]["path"], small_estimator_model, stature_m=1.86)
    _upload(browser, url, frames["one"]["path"], height_cm="186", mass_kg="84")
    _wait(browser, "document.body.dataset.answer && document.getElementById('viewer').dataset.triangles > 0")
    shown = _answer(browser)
    assert float(shown["wbsa"]) == pytest.approx(est.wbsa_m2, abs=5e-4) and shown["text"] == f"{est.wbsa_m2:.2f}"
    interval = browser.find_element("id", "interval").text
    # the page rounds the answer's 3 decimals to 2 (2.8554 -> 2.855 -> 2.85): off by up to 0.0055
    lo, hi = (float(v) for v in re.search(r"([\d.]+) – ([\d.]+) m²", interval).groups())
    assert lo == pytest.approx(est.wbsa_lo_m2, abs=0.006) and hi == pytest.approx(est.wbsa_hi_m2, abs=0.006)
    assert "95 % interval" in interval
    assert "regression" in browser.find_element("id", "method-line").text
    assert shown["flagNames"] == list(est.flags) and est.flags
    for name, text in zip(est.flags, shown["flags"]):
        assert FLAGS[name][1:] in text
    assert not COMMAND_LINE_WORDS.search(_page_text(browser)), _page_text(browser)
    assert not _shown(browser, "routes") and not _shown(browser, "pick-card")  # one method: one number
    assert browser.execute_script("return [...document.querySelectorAll('#viewer-legend li')].map(li => li.dataset.mesh)"
                                  ) == ["visible surface"]
    assert int(shown["triangles"]) == len(est.surface.faces) and shown["depthWidth"] == 512
    assert browser.execute_script("return document.querySelectorAll('#sketch *').length") > 5
    assert shown["formulae"] == 14 and shown["error"] == ""  # wbsa's row and the 13 formulae (Schlich twice)
    assert [Path(h).name for h in shown["downloads"]] == ["estimate.json", "fhir.json", "mask.png", "surface.ply"]
    with urllib.request.urlopen(url + shown["downloads"][1]) as r:
        assert json.loads(r.read())["valueQuantity"]["value"] == round(est.wbsa_m2, 4)
    _screenshot(browser, "serve-answer.png")
    # the side view draws the whole range of elevations, -90° (camera below) to 90° (above), inside the sketch
    for elevation in (-90, -60, 0, 60, 90):
        inside = browser.execute_script("""
            showView({...current.view, elevation_used_deg: arguments[0]});
            const box = document.getElementById('sketch').getBoundingClientRect();
            const cam = document.getElementById('side-camera').getBoundingClientRect();
            return [cam.left >= box.left, cam.right <= box.right, cam.top >= box.top, cam.bottom <= box.bottom,
                    cam.top + cam.height / 2 - (box.top + box.height / 2)];""", elevation)
        assert inside[:4] == [True] * 4, (elevation, inside)
        assert np.sign(round(inside[4])) == -np.sign(elevation)  # above the middle for a camera above


def test_a_click_on_the_second_person_measures_that_person(server, browser, frames, small_estimator_model):
    """Two people: the page says so and shows the depth picture; a click on the woman gives wbsa.estimate's
    answer for the pixel clicked (hers), a click on the man then gives his."""
    from selenium.webdriver.common.action_chains import ActionChains

    url, _ = server
    two = frames["two"]
    browser.set_window_size(1280, 800)  # a laptop's window: the picture must fit in it
    try:
        _upload(browser, url, two["path"])
        _wait(browser, "!document.getElementById('pick-card').hidden && document.getElementById('depth-img').naturalWidth"
                       " > 0 && document.getElementById('depth-img').getBoundingClientRect().top >= 0")
        title = browser.find_element("id", "pick-title").text
        assert "2 people in the depth image" in title and "click on the person to measure" in title
        assert not COMMAND_LINE_WORDS.search(_page_text(browser)), _page_text(browser)
        # no answer: no number, sketch, 3-D view or downloads; the picture large and wholly in the window
        for card in ("answer", "sketch-card", "viewer-card", "downloads-card", "depth-card", "flags", "no-flags"):
            assert not _shown(browser, card), card
        box = browser.execute_script("const r = document.getElementById('depth-img').getBoundingClientRect(); "
                                     "return [r.top, r.bottom, r.width, window.innerHeight]")
        assert 0 <= box[0] and box[1] <= box[3] and box[2] >= 560, box  # above the fold, wider than the file's 512 px
        _screenshot(browser, "serve-several-people.png")
    finally:
        browser.set_window_size(1280, 1900)
    img = browser.find_element("id", "depth-img")
    results = {}
    for who in ("woman", "man"):
        ys, xs = np.nonzero(two[who])
        x, y = int(np.median(xs)), int(np.median(ys[xs == int(np.median(xs))]))  # a pixel on the body's axis
        before = _answer(browser)["id"]
        w = browser.execute_script("return arguments[0].clientWidth", img)
        h = browser.execute_script("return arguments[0].clientHeight", img)
        ActionChains(browser).move_to_element_with_offset(img, int((x + 0.5) * w / 512 - w / 2),
                                                          int((y + 0.5) * h / 424 - h / 2)).click().perform()
        _wait(browser, f"document.body.dataset.answer && document.body.dataset.answer !== '{before}' "
                       "&& document.body.dataset.busy === '0'")
        pick = browser.execute_script("return fetch('api/result/' + document.body.dataset.answer + '/estimate.json')"
                                      ".then(r => r.json())")
        shown = _answer(browser)
        answer_pick = tuple(browser.execute_script("return current.pick"))
        assert two[who][answer_pick[1], answer_pick[0]], (who, answer_pick)
        est = _estimate(two["path"], small_estimator_model, pick=answer_pick)
        assert float(shown["wbsa"]) == pytest.approx(est.wbsa_m2, abs=5e-4) and pick["n_pixels"] == est.n_pixels
        results[who] = est
    assert results["woman"].wbsa_m2 != results["man"].wbsa_m2
    assert results["woman"].stature_m < results["man"].stature_m - 0.05  # she is 1.72 m, he 1.86 m


def test_a_bad_file_shows_its_error_and_the_server_still_answers(server, browser, frames, tmp_path):
    """A text file renamed .png and the header of a 100-megapixel image: the page shows the message; the next
    file is answered. Two files give the batch table with its CSV."""
    url, _ = server
    text = tmp_path / "notes.png"
    text.write_text("this is not a depth image\n")
    huge = tmp_path / "huge.png"
    huge.write_bytes(_png_header(10_000, 10_000))
    for path, words in ((text, "notes.png is not a .png file"), (huge, "100.0 megapixels) is above wbsa's limit")):
        _upload(browser, url, path)
        _wait(browser, "!document.getElementById('error').hidden")
        assert words in _answer(browser)["error"]
    _upload(browser, url, frames["one"]["path"])
    _wait(browser, "document.body.dataset.answer")
    assert _answer(browser)["error"] == ""
    _upload(browser, url, frames["one"]["path"], text)
    _wait(browser, "document.getElementById('batch-csv').hidden === false", timeout=60)
    rows = browser.execute_script("return [...document.querySelectorAll('#batch-table tbody tr')]"
                                  ".map(tr => [...tr.children].map(td => td.textContent))")
    assert len(rows) == 2 and rows[0][0] == "one.png" and float(rows[0][1]) > 1.0 and "is not a .png" in rows[1][4]
    assert browser.find_element("id", "batch-count").text == "2 of 2 done"


def test_method_both_shows_each_route_which_leads_and_the_progress_of_the_fit(server, browser, frames,
                                                                             small_estimator_model):
    """Method both: each route's own number, interval and flags beside the leading number, which leads and why,
    the 3-D view's two bodies with a legend; while it runs, the stages and the body fit's steps are shown."""
    import wbsa
    from selenium.webdriver.common.by import By

    from wbsa.estimation import SegmentSettings

    url, _ = server
    _upload(browser, url, camera="kinect-v2", method="both")
    browser.find_element(By.ID, "depth-file").send_keys(str(frames["one"]["path"]))
    _wait(browser, "document.body.dataset.answer && document.body.dataset.busy === '0' "
                   "&& document.getElementById('viewer').dataset.triangles > 0", timeout=300)
    log = browser.execute_script("return window.progressLog")
    stages = [p["stage"] for p in log]
    assert [s for i, s in enumerate(stages) if i == 0 or stages[i - 1] != s] == \
        ["reading", "subject", "regression", "body-fit", "answer"], stages
    steps = [p["done"] for p in log if p["stage"] == "body-fit" and p["total"] > 1]
    totals = {p["total"] for p in log if p["stage"] == "body-fit" and p["total"] > 1}
    assert steps and steps == sorted(steps) and 0 < steps[-1] <= FIT_STEPS and totals == {FIT_STEPS}  # in order
    est = wbsa.estimate(str(frames["one"]["path"]), "kinect-v2", str(small_estimator_model), method="both",
                        clothes="underwear", segment=SegmentSettings(), body_fit=_fit_settings())
    routes = browser.execute_script("""return [...document.querySelectorAll('#route-list .route')].map(b => ({
        name: b.dataset.route, leads: b.classList.contains('leads'), text: b.innerText,
        flags: [...b.querySelectorAll('li')].map(li => li.dataset.flag)}))""")
    assert [r["name"] for r in routes] == ["regression", "body-fit"] == list(est.routes)
    for shown, (name, p) in zip(routes, est.routes.items()):
        assert f"{p.wbsa_m2:.2f} m²" in shown["text"] and f"{p.wbsa_lo_m2:.2f} – {p.wbsa_hi_m2:.2f} m²" in shown["text"]
        assert shown["flags"] == list(p.flags) and shown["leads"] == (name == "regression")
    assert float(_answer(browser)["wbsa"]) == pytest.approx(est.routes["regression"].wbsa_m2, abs=5e-4)
    assert "Regression (leads)" == browser.find_element(By.ID, "lead-label").text
    assert "regression leads" in browser.find_element(By.ID, "lead-why").text
    image_flags = _answer(browser)["flagNames"]  # the picture's own checks, apart from the routes'
    assert set(image_flags) <= set(est.flags) and not set(image_flags) & set(est.routes["body-fit"].flags)
    legend = browser.execute_script("return [...document.querySelectorAll('#viewer-legend li')].map(li => li.innerText)")
    assert len(legend) == 2 and "measured" in legend[0] and "body fit" in legend[1]
    assert not COMMAND_LINE_WORDS.search(_page_text(browser))
    _screenshot(browser, "serve-both.png")


@pytest.mark.slow
def _device(driver, width: int, height: int, mobile: bool) -> None:
    """Emulate a screen of ``width`` × ``height`` CSS pixels (a phone with ``mobile``: its viewport rules)."""
    driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                           {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": mobile})


#: Where the page's progress and answer lie in the window: the progress card's box when it first shows (a
#: MutationObserver sees it right after the page made it visible), the number's box, the window's size and
#: the page's scroll width.
_IN_VIEW = """
const box = id => { const r = document.getElementById(id).getBoundingClientRect(); return [r.top, r.bottom]; };
return {progress: window.progressSeen, answer: box('wbsa-value'), height: innerHeight, width: innerWidth,
        scrollWidth: document.documentElement.scrollWidth};"""


def _watch_progress(driver) -> None:
    """Record the progress card's box when it first shows (``window.progressSeen``)."""
    driver.execute_script("""
        window.progressSeen = null;
        const p = document.getElementById('progress');
        new MutationObserver(() => { if (!p.hidden && window.progressSeen === null) {
            const r = p.getBoundingClientRect(); window.progressSeen = [r.top, r.bottom]; } })
          .observe(p, {attributes: true});""")


def _answer_at(driver, url, path, width: int, height: int, mobile: bool) -> dict:
    """Measure ``path`` on the page in a ``width`` × ``height`` window: where the progress and the answer lay."""
    from selenium.webdriver.common.by import By

    _device(driver, width, height, mobile)
    _upload(driver, url, height_cm="186", mass_kg="84")
    _watch_progress(driver)
    driver.find_element(By.ID, "depth-file").send_keys(str(path))
    _wait(driver, "document.body.dataset.answer && document.getElementById('viewer').dataset.triangles > 0")
    return driver.execute_script(_IN_VIEW)


def test_at_phone_width_the_progress_and_the_answer_scroll_into_view_and_nothing_overflows(server, browser, frames):
    """390 × 844, a phone's viewport: the form fills the screen, so the page scrolls the progress into view
    when it starts and the answer when it comes; nothing is wider than the screen."""
    url, _ = server
    try:
        seen = _answer_at(browser, url, frames["one"]["path"], 390, 844, mobile=True)
    finally:
        browser.execute_cdp_cmd("Emulation.clearDeviceMetricsOverride", {})
    assert seen["width"] == 390 and seen["scrollWidth"] <= seen["width"], seen
    # in view: inside the window, to a pixel (a box scrolled to the window's edge may end a fraction past it)
    assert seen["progress"] is not None and 0 <= seen["progress"][0] and seen["progress"][1] <= seen["height"] + 1, seen
    assert 0 <= seen["answer"][0] and seen["answer"][1] <= seen["height"] + 1, seen


def test_the_readme_picture_is_the_shipped_default_models_answer(browser, frames, tmp_path):
    """The page as ``wbsa serve`` starts it (no --model: wbsa.estimate's default model) on the tests' frame: its
    number is the default model's, in view at a desktop's 1280 × 900 and a phone's 390 × 844, and both windows
    are saved (test-artefacts/serve-page.png and serve-page-phone.png, the pictures of docs/serve.md and the
    README)."""
    import wbsa
    from wbsa.server.app import create_app
    from wbsa.server.command import start_in_thread

    app = create_app(None, temp_dir=str(tmp_path))
    url, stop = start_in_thread(app)
    est = wbsa.estimate(str(frames["one"]["path"]), "kinect-v2", clothes="underwear", stature_m=1.86)  # as typed
    try:
        for name, width, height, mobile in (("serve-page.png", 1280, 900, False),
                                            ("serve-page-phone.png", 390, 844, True)):
            seen = _answer_at(browser, url, frames["one"]["path"], width, height, mobile)
            shown = _answer(browser)
            assert float(shown["wbsa"]) == pytest.approx(est.wbsa_m2, abs=5e-4) and shown["flagNames"] == list(est.flags)
            assert browser.execute_script("return current.model") == est.model  # the default model's name
            assert 0 <= seen["answer"][0] and seen["answer"][1] <= seen["height"] + 1 and seen["scrollWidth"] <= width, seen
            _screenshot(browser, name)
    finally:
        browser.execute_cdp_cmd("Emulation.clearDeviceMetricsOverride", {})
        stop()


def test_clothes_are_a_choice_the_page_requires_and_states(server, browser, frames, small_estimator_model):
    """A file chosen before the clothes is not measured: the page asks for the clothes in plain words; choosing
    them measures it, stated (clothing_stated, the layer's name), with wbsa.estimate's answer for those clothes."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    import wbsa
    from wbsa.estimation import SegmentSettings
    from wbsa.estimation.clothes import CLOTHES

    url, _ = server
    _upload(browser, url, frames["one"]["path"], clothes="")
    _wait(browser, "!document.getElementById('error').hidden")
    assert "Choose what the person wears" in _answer(browser)["error"] and not _shown(browser, "result")
    assert browser.execute_script("return window.progressLog.length") == 0  # nothing was sent
    options = browser.execute_script("return [...document.getElementById('clothes').options].map(o => o.value)")
    assert options == ["", *CLOTHES]
    Select(browser.find_element(By.ID, "clothes")).select_by_value("street")
    _wait(browser, "document.body.dataset.answer && document.body.dataset.busy === '0'")
    with urllib.request.urlopen(url + f"api/result/{_answer(browser)['id']}/estimate.json") as r:
        stated = json.loads(r.read())
    assert stated["clothes"] == "street" and stated["clothing_stated"] is True
    assert "clothes_unstated" not in _answer(browser)["flagNames"]
    est = wbsa.estimate(str(frames["one"]["path"]), "kinect-v2", str(small_estimator_model), clothes="street",
                        segment=SegmentSettings())
    assert float(_answer(browser)["wbsa"]) == pytest.approx(est.wbsa_m2, abs=5e-4)
    assert not COMMAND_LINE_WORDS.search(_page_text(browser))


def test_intrinsics_chosen_after_the_depth_file_run_it_again(server, browser, frames, small_estimator_model,
                                                             tmp_path):
    """The depth file first (camera from the image size: assumed, flagged), then the camera's intrinsics file: the
    page measures the file again with them, says so, and shows wbsa.estimate's answer with that camera."""
    from selenium.webdriver.common.by import By

    from wbsa.camera import preset

    url, _ = server
    cam = tmp_path / "cam.json"
    cam.write_text(json.dumps(preset("kinect-v2").to_open3d_json()))
    _upload(browser, url, frames["one"]["path"], camera="auto")
    _wait(browser, "document.body.dataset.answer && document.body.dataset.busy === '0'")
    first = _answer(browser)
    assert "camera_assumed" in first["flagNames"] and browser.execute_script("return window.progressLog.length") >= 3
    browser.find_element(By.ID, "intrinsics").send_keys(str(cam))
    _wait(browser, f"document.body.dataset.reruns === '1' && document.body.dataset.answer "
                   f"&& document.body.dataset.answer !== '{first['id']}' && document.body.dataset.busy === '0'")
    again = _answer(browser)
    note = browser.find_element(By.ID, "rerun-note").text
    assert "Measured again with the camera file cam.json" in note and _shown(browser, "rerun-note")
    assert "camera_assumed" not in again["flagNames"]
    est = _estimate(frames["one"]["path"], small_estimator_model)
    assert float(again["wbsa"]) == pytest.approx(est.wbsa_m2, abs=5e-4)
    _screenshot(browser, "serve-rerun-intrinsics.png")


def test_messages_reach_the_page_in_its_own_words(server, browser, frames, tmp_path, small_estimator_model):
    """The library's messages carry command-line words; the page shows every one of them in its own words
    (wbsa.errors.page_text): real messages from the library, and an 8-bit picture dropped on the page."""
    from PIL import Image

    import wbsa
    from wbsa.camera import preset
    from wbsa.errors import WbsaError
    from wbsa.estimation.methods.base import Request
    from wbsa.estimation.methods.body_fit.predictor import BodyFitPredictor
    from wbsa.estimation.methods.view import ViewEstimate, view_used
    from wbsa.estimation.clothes import check_clothing
    from wbsa.estimation.subject import checks
    from wbsa.errors import command_text, page_text

    def message(call, *args) -> WbsaError:
        with pytest.raises(WbsaError) as err:
            call(*args)
        return err.value

    grey = tmp_path / "photo.png"
    Image.fromarray(np.full((424, 512), 128, np.uint8)).save(grey)
    from wbsa.core.depth_image import read_depth

    cli = [
        message(checks.check_image_size, np.zeros((424, 512)), preset("kinect-v1")),
        message(check_clothing, 0.2),
        message(BodyFitPredictor().check_request, Request(level=0.8)),
        message(wbsa.estimate, str(frames["two"]["path"]), "kinect-v2", str(small_estimator_model)),
        view_used(ViewEstimate(131.0, 49.0, 12.0, 1.0, 0.41), None, None)[1]["uncertain_view"],
        checks.person_shape_flags(1.0, 2.0, 1.9)["not_a_person"],
        _fitted_at_the_model_edge(),  # the body fit's outside_model_range detail, as it writes it
    ]
    for text in cli:
        assert COMMAND_LINE_WORDS.search(command_text(text)), text  # the terminal's words name its options
        assert not COMMAND_LINE_WORDS.search(page_text(text)), (str(text), page_text(text))
    for flag in cli[4:6]:  # a flag's detail in Python names the argument, not the option
        assert "--" not in str(flag) and "--" in command_text(flag), (str(flag), command_text(flag))
    assert cli[3].code == "choose_person" and "click on the person" in page_text(cli[3]) and cli[0].code != "choose_person"
    picture = message(read_depth, grey)  # plain words for both: what the picture is, never Pillow's mode letter
    assert page_text(picture) == str(picture) and not COMMAND_LINE_WORDS.search(str(picture))
    url, _ = server
    _upload(browser, url, grey)
    _wait(browser, "!document.getElementById('error').hidden && document.body.dataset.busy === '0'")
    error = _answer(browser)["error"]
    assert "photo.png is an 8-bit grey-scale picture, not a 16-bit depth image" in error
    assert not COMMAND_LINE_WORDS.search(_page_text(browser))
    assert not _shown(browser, "result")  # nothing measured: no cards at all


def test_the_progress_stream_ends_with_the_answer_a_script_gets(server, frames):
    """Accept: application/x-ndjson gives the stages as JSON lines and, last, the answer with its status; the same
    request without it gets the one JSON answer, with the same number."""
    url, _ = server
    body, ctype = _form({"camera": "kinect-v2"}, [("depth", "one.png", frames["one"]["path"].read_bytes())])
    req = urllib.request.Request(url + "api/estimate", data=body, method="POST",
                                 headers={"Content-Type": ctype, "Accept": "application/x-ndjson"})
    with urllib.request.urlopen(req, timeout=120) as r:
        assert r.headers["Content-Type"].startswith("application/x-ndjson")
        lines = [json.loads(line) for line in r.read().decode().splitlines()]
    stages = [line["progress"]["stage"] for line in lines[:-1]]
    assert stages == ["reading", "subject", "regression", "answer"]
    assert lines[-1]["status"] == 200
    code, plain = _post(url, {"camera": "kinect-v2"}, [("depth", "one.png", frames["one"]["path"].read_bytes())])
    assert code == 200 and plain["wbsa_m2"] == lines[-1]["answer"]["wbsa_m2"] and plain["id"] != lines[-1]["answer"]["id"]
    # an answer without a result is the last line too, with the status a plain request gets
    body, ctype = _form({"camera": "kinect-v2"}, [("depth", "two.png", frames["two"]["path"].read_bytes())])
    req = urllib.request.Request(url + "api/estimate", data=body, method="POST",
                                 headers={"Content-Type": ctype, "Accept": "application/x-ndjson"})
    with urllib.request.urlopen(req, timeout=120) as r:
        last = json.loads(r.read().decode().splitlines()[-1])
    assert last["status"] == 422 and last["answer"]["choose_person"] and "click on the person" in last["answer"]["error"]


# ---------------------------------------------------------------- the routes and bad input
def _png_header(width: int, height: int) -> bytes:
    """A PNG signature and IHDR chunk announcing a ``width`` x ``height`` 16-bit grey image (no pixel data)."""
    ihdr = struct.pack(">IIBBBBB", width, height, 16, 0, 0, 0, 0)
    chunk = b"IHDR" + ihdr
    return b"\x89PNG\r\n\x1a\n" + struct.pack(">I", len(ihdr)) + chunk + struct.pack(">I", zlib.crc32(chunk))


def _form(fields: dict, files: list[tuple[str, str, bytes]], boundary: str = "wbsaTEST") -> tuple[bytes, str]:
    parts = []
    for name, value in fields.items():
        parts.append(f'--{boundary}\r\nContent-Disposition: form-data; name="{name}"\r\n\r\n{value}\r\n'.encode())
    for name, filename, data in files:
        parts.append(f'--{boundary}\r\nContent-Disposition: form-data; name="{name}"; filename="{filename}"\r\n'
                     "Content-Type: application/octet-stream\r\n\r\n".encode() + data + b"\r\n")
    parts.append(f"--{boundary}--\r\n".encode())
    return b"".join(parts), f"multipart/form-data; boundary={boundary}"


def _post(url: str, fields: dict | None = None, files=(), path: str = "api/estimate") -> tuple[int, dict]:
    body, ctype = _form(fields or {}, list(files))
    req = urllib.request.Request(url + path, data=body, headers={"Content-Type": ctype}, method="POST")
    try:
        with urllib.request.urlopen(req, timeout=120) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as err:
        return err.code, json.loads(err.read())


def _alive(url: str) -> bool:
    with urllib.request.urlopen(url + "api/info", timeout=30) as r:
        return r.status == 200 and "kinect-v2" in r.read().decode()


def test_every_bad_input_gets_one_clear_line_and_the_server_keeps_running(server, frames):
    url, app = server
    good, two = frames["one"]["path"].read_bytes(), frames["two"]["path"].read_bytes()
    empty_npy = io.BytesIO()
    np.save(empty_npy, np.zeros((0, 0), np.float32))
    cases = [
        ({}, [("depth", "notes.png", b"plain text, renamed")], 415, "notes.png is not a .png file"),
        ({}, [("depth", "frame.jpg", b"\xff\xd8\xff")], 415, "not a depth file type wbsa reads"),
        ({}, [("depth", "empty.png", b"")], 400, "empty.png is empty (0 bytes)"),
        ({}, [("depth", "zero.png", _png_header(0, 0))], 400, "says 0 x 0 pixels: it holds no image"),
        ({}, [("depth", "zero.npy", empty_npy.getvalue())], 400, "says 0 x 0 pixels"),
        ({}, [("depth", "huge.png", _png_header(100_000, 100_000))], 413, "10000.0 megapixels) is above"),
        ({}, [("depth", "cut.png", good[:2000])], 422, "cut.png is not a readable image"),
        ({}, [("depth", "one.png", good), ("intrinsics", "cam.json", b"not json")], 400,
         "cam.json is not an intrinsics JSON"),
        ({}, [("depth", "one.png", good), ("intrinsics", "cam.json", b'{"width": 512}')], 400,
         "cam.json: camera JSON lacks 'intrinsic_matrix'"),
        ({"camera": "kinect-v1"}, [("depth", "one.png", good)], 422, "is 512x424 but camera kinect-v1 is 640x480"),
        ({"camera": "/etc/passwd"}, [("depth", "one.png", good)], 400, "holds a file path"),
        ({"camera": "../cam.json"}, [("depth", "one.png", good)], 400, "holds a file path"),
        ({"camera": "kinect-v9"}, [("depth", "one.png", good)], 400, "'kinect-v9' is not a preset"),
        ({"clothing_cm": "thick"}, [("depth", "one.png", good)], 400, "clothing_cm: expected a thickness"),
        ({"pick": "middle"}, [("depth", "one.png", good)], 400, "nearest, largest, center or x,y"),
        ({"pick": "5000,5"}, [("depth", "two.png", two)], 422, "lies outside the 512 x 424 depth image"),
        ({"sex": "x"}, [("depth", "one.png", good)], 400, "must be male or female"),
        ({"elevation_deg": "95"}, [("depth", "one.png", good)], 400, "elevation_deg: expected an elevation"),
        ({"model": "evil.npz"}, [("depth", "one.png", good)], 400, "unknown field 'model'"),
        ({}, [], 400, "no depth file was sent"),
    ]
    for fields, files, status, words in cases:
        code, body = _post(url, fields, files)
        assert (code, words in body.get("error", "")) == (status, True), (fields, [f[1] for f in files], code, body)
        assert "\n" not in body["error"] and str(app.state.root) not in json.dumps(body)
        assert "/tmp" not in body["error"], body
    # a form whose body ends before the form does: the upload was cut off
    body, ctype = _form({}, [("depth", "one.png", good)])
    req = urllib.request.Request(url + "api/estimate", data=body[:-200], headers={"Content-Type": ctype}, method="POST")
    with pytest.raises(urllib.error.HTTPError) as err:
        urllib.request.urlopen(req, timeout=30)
    assert err.value.code == 400 and "was cut off after" in json.loads(err.value.read())["error"]
    # a sender that goes away half-way through its announced body
    host, port = url.split("//")[1].strip("/").split(":")
    with socket.create_connection((host, int(port)), timeout=10) as s:
        s.sendall(f"POST /api/estimate HTTP/1.1\r\nHost: x\r\nContent-Type: {ctype}\r\n"
                  f"Content-Length: {len(body)}\r\n\r\n".encode() + body[: len(body) // 2])
    # a body above the limit is refused from its announced length, before any of it is read
    with socket.create_connection((host, int(port)), timeout=10) as s:
        s.sendall(f"POST /api/estimate HTTP/1.1\r\nHost: x\r\nContent-Type: {ctype}\r\n"
                  f"Content-Length: {9 * 2**20}\r\n\r\n".encode())
        reply = s.makefile("rb").read().decode()
    assert reply.startswith("HTTP/1.1 413") and "above this server's limit of 8 MiB" in reply, reply
    code, body = _post(url, {"azimuth_deg": "20", "elevation_deg": "12"}, [("depth", "one.png", good)])
    assert code == 200 and body["wbsa_lo_m2"] < body["wbsa_m2"] < body["wbsa_hi_m2"] and _alive(url)
    assert (body["view"]["azimuth_used_deg"], body["view"]["elevation_used_deg"]) == (20, 12)  # a stated view is used
    assert list(app.state.root.iterdir()) == []  # every estimate's folder removed


def test_fifty_uploads_at_once_are_answered_or_told_the_server_is_busy(small_estimator_model, frames, tmp_path):
    """50 at once against a server with 4 places: each gets an answer or the one-line busy message, the server
    goes on, the estimates run off the event loop (the page loads while they run), and no folder is left.
    (20 at once, all answered, on the default 32 places: benchmarks/bench_serve.py.)"""
    from wbsa.server.app import create_app
    from wbsa.server.command import start_in_thread

    app = create_app(small_estimator_model, temp_dir=str(tmp_path), max_pending=4)
    url, stop = start_in_thread(app)
    good = frames["one"]["path"].read_bytes()
    out = []

    def one() -> None:
        out.append(_post(url, {"camera": "kinect-v2"}, [("depth", "one.png", good)]))

    threads = [threading.Thread(target=one) for _ in range(50)]
    for t in threads:
        t.start()
    with urllib.request.urlopen(url, timeout=10) as r:  # the event loop is free while estimates run
        assert r.status == 200
    for t in threads:
        t.join()
    codes = [c for c, _ in out]
    assert len(out) == 50 and set(codes) == {200, 503} and codes.count(200) >= 4, codes
    assert len({b["wbsa_m2"] for c, b in out if c == 200}) == 1  # the same answer from every thread
    assert all("the server is busy" in b["error"] for c, b in out if c == 503)
    assert _alive(url) and app.state.runner.pending == 0 and list(app.state.root.iterdir()) == []
    stop()
    assert not app.state.root.exists()


def test_a_batch_gives_one_row_per_file_and_a_csv(server, frames, small_estimator_model):
    import csv
    import io
    import time

    url, _ = server
    good = frames["one"]["path"].read_bytes()
    code, batch = _post(url, {"camera": "kinect-v2"},
                        [("depth", "a.png", good), ("depth", "b.txt", b"x"), ("depth", "c.png", good)], "api/batch")
    assert code == 200 and batch["total"] == 3
    for _ in range(600):
        with urllib.request.urlopen(url + f"api/batch/{batch['id']}") as r:
            batch = json.loads(r.read())
        if batch["done"]:
            break
        time.sleep(0.1)
    assert batch["done_count"] == 3
    with urllib.request.urlopen(url + batch["csv"]) as r:
        rows = list(csv.DictReader(io.StringIO(r.read().decode())))
    est = _estimate(frames["one"]["path"], small_estimator_model, clothes=None)  # a script that states none
    assert [r["file"] for r in rows] == ["a.png", "b.txt", "c.png"]
    assert float(rows[0]["wbsa_m2"]) == pytest.approx(est.wbsa_m2, abs=5e-4) and rows[0]["flags"] == ";".join(est.flags)
    assert rows[1]["wbsa_m2"] == "" and "not a depth file type" in rows[1]["error"]
    # nothing stated of the clothes or the stature: the CSV says so
    assert (rows[0]["clothing_stated"], rows[0]["clothes"], rows[0]["stature_stated_m"]) == ("False", "", "")
    assert "clothes_unstated" in rows[0]["flags"].split(";")


def test_the_page_reads_each_flags_meaning_and_advice_from_its_record():
    from wbsa.estimation.flags import DEFAULT_ADVICE, FLAG_RECORDS
    from wbsa.server.advice import flag_rows

    row, unknown = flag_rows({"cut_off": "subject pixels on the image border", "new_flag": "detail"})
    assert row == {"name": "cut_off", "meaning": FLAG_RECORDS["cut_off"].meaning,
                   "detail": "subject pixels on the image border", "todo": FLAG_RECORDS["cut_off"].advice}
    assert unknown["meaning"] == "new flag" and unknown["todo"] == DEFAULT_ADVICE


def test_upload_names_never_carry_folders_and_messages_never_carry_the_servers_paths():
    from wbsa.server.uploads import display_name, scrub

    assert display_name("../../etc/passwd.png") == "passwd.png" and display_name("C:\\a\\b.npy") == "b.npy"
    assert display_name("\x00\x1b.png") == ".png" and len(display_name("x" * 500 + ".png")) <= 100
    assert scrub("/srv/t/wbsa-serve-1/r-2/depth.png is not readable", "/srv/t/wbsa-serve-1/r-2", "a.png") == \
        "a.png is not readable"


def test_a_wildcard_host_is_printed_as_the_machines_own_addresses():
    """0.0.0.0 and :: are no address to open: the page's addresses are this machine's own (each can be bound
    here), never a wildcard; any other host is printed as given."""
    from wbsa.server.addresses import machine_hosts, page_urls

    for wildcard in ("0.0.0.0", "::"):
        hosts = machine_hosts(wildcard)
        assert hosts and not set(hosts) & {"0.0.0.0", "::", ""}
        for host in hosts:
            family = socket.AF_INET6 if ":" in host else socket.AF_INET
            if host[0].isdigit() or ":" in host:  # an address: one of this machine's
                with socket.socket(family, socket.SOCK_STREAM) as s:
                    s.bind((host, 0))
            else:  # its name
                assert host == socket.gethostname()
    assert page_urls("127.0.0.1", 8080, "?token=t") == ["http://127.0.0.1:8080/?token=t"]
    assert page_urls("::1", 8080) == ["http://[::1]:8080/"]


@pytest.mark.slow
def test_wbsa_serve_prints_its_address_and_serves_the_page(small_estimator_model):
    """Listening on every interface, the printed address is the machine's own, token included, and opens the page."""
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-m", "wbsa", "serve", "--model", str(small_estimator_model), "--host",
                             "0.0.0.0", "--token", "a-token-of-the-users-0123"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        assert line.startswith("wbsa serve: open http://"), (line, proc.stderr.read() if proc.poll() else "")
        address = line.split()[3]
        assert "0.0.0.0" not in line and address.endswith("/?token=a-token-of-the-users-0123"), line
        with urllib.request.urlopen(address, timeout=30) as r:
            page = r.read().decode()
        assert "Body surface area from one depth image" in page and "https://" not in page
    finally:
        proc.terminate()
        proc.wait(timeout=30)
    bad = subprocess.run([sys.executable, "-m", "wbsa", "serve", "--model", "/nonexistent/m.npz"],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and bad.stderr.startswith("error:") and bad.stderr.count("\n") == 1, bad.stderr


@pytest.mark.slow
def test_the_body_fit_route_shows_and_offers_the_fitted_body(server, frames):
    """method=body-fit: the answer is the body fit's, the 3-D view gets the fitted body beside the visible surface,
    and the body is offered at rest and as seen (PLY, the writers of wbsa estimate --out-body)."""
    url, _ = server
    status, answer = _post(url, {"method": "body-fit"}, [("depth", "one.png", frames["one"]["path"].read_bytes())])
    assert status == 200 and answer["method"] == "body-fit", answer
    assert [m["name"] for m in answer["meshes"]] == ["visible surface", "fitted body"]
    urls = {d["label"]: d["url"] for d in answer["downloads"]}
    with urllib.request.urlopen(url + urls["Fitted body PLY (at rest)"], timeout=60) as r:
        assert r.read(3) == b"ply"


def test_beyond_loopback_every_request_needs_the_token_and_nothing_runs_without_it(small_estimator_model, frames):
    import http.cookiejar

    from wbsa.errors import WbsaError
    from wbsa.server.access import choose_token
    from wbsa.server.app import create_app
    from wbsa.server.command import start_in_thread

    assert choose_token("127.0.0.1", None) is None and choose_token("::1", "") is None
    made = choose_token("0.0.0.0", None)
    assert len(made) >= 40 and made != choose_token("0.0.0.0", None)
    with pytest.raises(WbsaError, match="at least 16"):
        choose_token("0.0.0.0", "short")
    token = "a-token-of-the-users-0123"
    app = create_app(small_estimator_model, token=token)
    url, stop = start_in_thread(app)
    try:
        good = frames["one"]["path"].read_bytes()
        for path in ("", "api/info", "static/app.js", "api/batch/x", "api/result/x/estimate.json"):
            with pytest.raises(urllib.error.HTTPError) as refused:
                urllib.request.urlopen(url + path, timeout=30)
            assert refused.value.code == 403 and b"token" in refused.value.read()
        code, body = _post(url, {"camera": "kinect-v2"}, [("depth", "one.png", good)])
        assert code == 403 and "token" in body["error"]
        code, body = _post(url + f"?token=wrong-{token}", {"camera": "kinect-v2"}, [("depth", "one.png", good)])
        assert code == 403
        assert app.state.runner.pending == 0 and len(app.state.results) == 0  # nothing was computed or kept
        # the printed address sets the cookie; the page's later requests carry it
        jar = http.cookiejar.CookieJar()
        opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor(jar))
        with opener.open(url + f"?token={token}", timeout=30) as r:
            assert r.status == 200 and "Body surface area" in r.read().decode()
        with opener.open(url + "api/info", timeout=30) as r:
            assert r.status == 200
        req = urllib.request.Request(url + "api/info", headers={"Authorization": f"token {token}"})
        with urllib.request.urlopen(req, timeout=30) as r:
            assert r.status == 200
    finally:
        stop()
