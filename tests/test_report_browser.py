"""The report in a real browser (Debian's headless Chromium) at 1280 px: every table fits the page.

The browser measures each table's bounding box against the width of the page's content (the body's content
box) and the page against the window; screenshots of the whole default report are left in
``test-artefacts/report-1280-NN.png`` (top to bottom) for a person to look at.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from helpers.browser import ARTEFACTS, headless_chromium
from wbsa.report.html import Page

WIDTH = 1280

#: Widths in CSS pixels: the body's content box, the window's and the page's (scrollWidth), and every table's
#: own box and the box it sits in (with the box's scrollable width).
MEASURE = """
const body = document.body, cs = getComputedStyle(body);
const content = body.getBoundingClientRect().width - parseFloat(cs.paddingLeft) - parseFloat(cs.paddingRight);
const tables = [...document.querySelectorAll('table')].map(t => {
  const box = t.parentElement;
  return {id: t.id, width: t.getBoundingClientRect().width, box: box.getBoundingClientRect().width,
          box_scroll: box.scrollWidth, box_client: box.clientWidth};
});
const figures = [...document.querySelectorAll('figure img')].map(i => ({
  id: i.parentElement.id, width: i.getBoundingClientRect().width}));
return {content: content, window: document.documentElement.clientWidth,
        page: document.documentElement.scrollWidth, tables: tables, figures: figures};
"""


@pytest.fixture(scope="module")
def browser():
    with headless_chromium(WIDTH, 1000) as driver:
        yield driver


def _measure(browser, path) -> dict:
    browser.set_window_size(WIDTH, 1000)
    browser.get(path.as_uri())
    return browser.execute_script(MEASURE)


def _full_page_screenshots(browser, stem: str, tile_px: int = 8000) -> list:
    """Screenshots of the whole page, top to bottom, ``tile_px`` high each (one Chromium screenshot stops at
    16,384 px; a report is longer): ``ARTEFACTS/<stem>-01.png``, ``-02.png``, ... The last tile ends at the page's
    bottom, so it may repeat the end of the one before."""
    height = int(browser.execute_script("return document.documentElement.scrollHeight"))
    browser.set_window_size(WIDTH, tile_px)
    view = int(browser.execute_script("return window.innerHeight"))
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    for old in ARTEFACTS.glob(f"{stem}-*.png"):
        old.unlink()
    shots = []
    for i, top in enumerate(range(0, height, view), start=1):
        browser.execute_script(f"window.scrollTo(0, {top})")
        shot = ARTEFACTS / f"{stem}-{i:02d}.png"
        browser.save_screenshot(str(shot))
        shots.append(shot)
    return shots


@pytest.mark.slow
def test_no_table_of_the_default_report_is_wider_than_the_page_at_1280_px(default_report, browser):
    m = _measure(browser, default_report)
    assert 1100 <= m["content"] <= m["window"] <= WIDTH
    ids = [t["id"] for t in m["tables"]]
    assert {"tab-claim", "tab-correlation", "tab-calibration", "tab-formulae", "tab-fits", "tab-settings"} <= set(ids)
    for t in m["tables"]:
        # the table itself fits (no sideways scrolling needed), and so does its box
        assert t["width"] <= m["content"] + 0.5, (t, m["content"])
        assert t["box"] <= m["content"] + 0.5 and t["box_scroll"] <= t["box_client"] + 1, t
    for f in m["figures"]:
        assert f["width"] <= m["content"] + 2.5, f  # the image and its 1 px border
    assert m["page"] <= m["window"], "the page scrolls sideways"
    shots = _full_page_screenshots(browser, "report-1280")
    assert shots and all(s.stat().st_size > 50_000 for s in shots)
    widths = {t["id"]: round(t["width"]) for t in m["tables"]}
    print(f"page content {m['content']:.0f} px; tables: {widths}")


def test_a_table_too_wide_for_any_page_scrolls_inside_its_own_box(browser, tmp_path):
    page = Page(title="a wide table")
    rng = np.random.default_rng(0)
    wide = pd.DataFrame(rng.normal(size=(4, 40)) * 1e6, columns=[f"unbreakable-column-{i}" for i in range(40)])
    page.table("tab-wide", wide, "Forty columns of seven-digit numbers.", nowrap=True)
    page.table("tab-small", wide.iloc[:, :3], "Three of them.")
    path = tmp_path / "wide.html"
    path.write_text(page.render())
    m = _measure(browser, path)
    big, small = m["tables"]
    assert big["width"] > 2 * m["content"]  # really wider than the page ...
    assert big["box"] <= m["content"] + 0.5 and big["box_scroll"] > big["box_client"]  # ... and scrolls in its box
    assert m["page"] <= m["window"]  # the page itself does not scroll sideways
    assert small["width"] < m["content"] and small["box_scroll"] <= small["box_client"] + 1
