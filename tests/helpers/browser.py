"""Headless Chromium for the tests that look at a page in a real browser (``wbsa serve``, the report).

Debian's ``/usr/bin/chromium`` driven by selenium through ``/usr/bin/chromedriver``, with a fresh profile and
the network features that would reach out (sync, component updates, QUIC) closed.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import uuid
from pathlib import Path
from typing import Iterator

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
#: Where tests leave what a person may want to look at (screenshots); git-ignored.
ARTEFACTS = Path(os.environ.get("WBSA_TEST_ARTEFACTS", Path(__file__).resolve().parents[2] / "test-artefacts"))


@contextlib.contextmanager
def headless_chromium(width: int = 1280, height: int = 1900) -> Iterator[object]:
    """A selenium Chrome driver of headless Chromium with a ``width`` × ``height`` window, quit on exit.

    Parameters
    ----------
    width, height : int
        The window size in CSS pixels (the page's viewport is this wide, less any scroll bar).

    Yields
    ------
    selenium.webdriver.Chrome
        The driver; its profile folder is removed when the context ends.
    """
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    profile = Path(os.environ.get("TMPDIR", "/tmp")) / f"wbsa-chromium-{uuid.uuid4().hex}"
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                "--disable-dev-shm-usage", f"--user-data-dir={profile}", f"--window-size={width},{height}"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    driver.set_page_load_timeout(30)
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)
