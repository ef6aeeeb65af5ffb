"""``wbsa serve`` on the loopback: page load, one estimate through the page's route, 20 estimates at once.

The server runs in this process (a thread, as in the tests) on a free 127.0.0.1 port. Figures:

1. page load: the page and everything it fetches (HTML, CSS, two scripts, ``api/info``) over HTTP, median of
   ``--repeat`` loads, and with ``--browser`` the load event in headless Chromium (navigation timing);
   ratio against a bare loopback round trip to the same server (``api/info`` alone);
2. one estimate: an upload to ``api/estimate`` (answer, depth picture, the four downloads made), median of
   ``--repeat``, as a ratio to a direct :func:`wbsa.estimate` call on the same file in the same run;
3. ``--n`` uploads at once (threads): every status, the median and worst latency, and the wall time for all,
   as ratios to the direct call.

The depth file is a rendered room with a known body in it (Kinect v2, the tests' frame) unless ``--depth``
gives one. Usage::

    python benchmarks/bench_serve.py --model small.npz            # a model file (see tests/conftest.py)
    python benchmarks/bench_serve.py                               # the default model
    python benchmarks/bench_serve.py --model small.npz --browser   # also the load event in Chromium
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path


def render_frame(path: Path) -> None:
    """The tests' frame: the reference man in a room, Kinect v2 at azimuth 20°, elevation 12°, 3.2 m."""
    from wbsa.bodies.anthropometry import reference_adult
    from wbsa.bodies.body_model import BodyModel
    from wbsa.camera import MeshScene, View, preset
    from wbsa.core import write_depth_png
    from wbsa.training.room import compose_room
    from wbsa.sensor.settings import SensorSettings
    from wbsa.simulate import simulate_view

    bm = BodyModel()
    man = bm.skin_mesh(bm.rest_bodies(reference_adult(0.0)).vertices[0])
    room = compose_room(man, 20.0, wall_behind_m=0.8)
    frame = simulate_view(MeshScene(room.mesh, surroundings=True), preset("kinect-v2"), View(20.0, 12.0, 3.2),
                          sensor=SensorSettings(noise="nguyen2012"), seed=4, keep_frame=True,
                          target=room.subject_center).frame
    write_depth_png(path, frame.depth_m)


def form(path: Path, camera: str) -> tuple[bytes, str]:
    """A ``multipart/form-data`` body with the depth file and the camera."""
    b = "wbsaBENCH"
    body = (f'--{b}\r\nContent-Disposition: form-data; name="camera"\r\n\r\n{camera}\r\n'
            f'--{b}\r\nContent-Disposition: form-data; name="depth"; filename="{path.name}"\r\n'
            "Content-Type: image/png\r\n\r\n").encode() + path.read_bytes() + f"\r\n--{b}--\r\n".encode()
    return body, f"multipart/form-data; boundary={b}"


def get(url: str) -> bytes:
    with urllib.request.urlopen(url, timeout=60) as r:
        return r.read()


def upload(url: str, body: bytes, ctype: str) -> tuple[int, float, dict]:
    """(status, seconds, answer) of one upload."""
    req = urllib.request.Request(url + "api/estimate", data=body, headers={"Content-Type": ctype}, method="POST")
    t = time.perf_counter()
    try:
        with urllib.request.urlopen(req, timeout=600) as r:
            status, answer = r.status, json.loads(r.read())
    except urllib.error.HTTPError as err:
        status, answer = err.code, json.loads(err.read())
    return status, time.perf_counter() - t, answer


def median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def browser_load(url: str, repeat: int) -> float:
    """Median load-event time (s) of the page in headless Chromium."""
    import shutil
    import uuid

    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    profile = Path(tempfile.gettempdir()) / f"wbsa-bench-chromium-{uuid.uuid4().hex}"
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                f"--user-data-dir={profile}"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    try:
        times = []
        for _ in range(repeat):
            driver.get(url)
            times.append(driver.execute_script(
                "const t = performance.getEntriesByType('navigation')[0]; return t.loadEventEnd - t.startTime") / 1000)
        return statistics.median(times)
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--model", default=None, help="estimator model (.npz); default: the default model")
    p.add_argument("--depth", default=None, help="a depth file (default: a rendered Kinect v2 room)")
    p.add_argument("--camera", default="kinect-v2", help="its camera preset (default kinect-v2)")
    p.add_argument("--n", type=int, default=20, help="uploads at once (default 20)")
    p.add_argument("--workers", type=int, default=2, help="the server's estimate threads (default 2)")
    p.add_argument("--repeat", type=int, default=5, help="repeats of the page load and single estimate (default 5)")
    p.add_argument("--browser", action="store_true", help="also time the page's load event in headless Chromium")
    args = p.parse_args(argv)

    import wbsa
    from wbsa.estimation import SegmentSettings
    from wbsa.server.app import create_app
    from wbsa.server.command import start_in_thread

    folder = Path(tempfile.mkdtemp(prefix="wbsa-bench-serve-"))
    depth = Path(args.depth) if args.depth else folder / "room.png"
    if not args.depth:
        render_frame(depth)
    app = create_app(args.model, workers=args.workers)
    model = app.state.model
    url, stop = start_in_thread(app)
    try:
        direct = lambda: wbsa.estimate(str(depth), args.camera, model, segment=SegmentSettings())  # noqa: E731
        direct()  # warm: imports, caches
        t_direct = median_time(direct, args.repeat)
        page = ["", "static/style.css", "static/viewer.js", "static/app.js", "api/info"]
        get(url)
        t_round = median_time(lambda: get(url + "api/info"), args.repeat * 4)
        t_page = median_time(lambda: [get(url + p) for p in page], args.repeat * 4)
        print(f"page load (HTML, CSS, 2 scripts, api/info over HTTP): {1000 * t_page:.1f} ms median of "
              f"{args.repeat * 4} = {t_page / t_round:.1f} x a bare loopback round trip ({1000 * t_round:.2f} ms)")
        if args.browser:
            t_browser = browser_load(url, args.repeat)
            print(f"page load event in headless Chromium: {1000 * t_browser:.0f} ms median of {args.repeat} "
                  f"= {t_browser / t_round:.0f} x the round trip")
        body, ctype = form(depth, args.camera)
        status, _, answer = upload(url, body, ctype)
        assert status == 200, answer
        t_one = statistics.median(upload(url, body, ctype)[1] for _ in range(args.repeat))
        print(f"direct wbsa.estimate: {t_direct:.2f} s median of {args.repeat} (the baseline)")
        print(f"one upload to api/estimate: {t_one:.2f} s median of {args.repeat} = {t_one / t_direct:.2f} x the "
              f"direct call (WBSA {answer['wbsa_m2']} m2)")
        results: list[tuple[int, float, dict]] = []
        threads = [threading.Thread(target=lambda: results.append(upload(url, body, ctype))) for _ in range(args.n)]
        t = time.perf_counter()
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        wall = time.perf_counter() - t
        latencies = sorted(r[1] for r in results)
        codes = sorted({r[0] for r in results})
        answered = sum(r[0] == 200 for r in results)
        print(f"{args.n} uploads at once ({args.workers} estimate threads): {answered} of {args.n} answered "
              f"(statuses {codes}); latency median {statistics.median(latencies):.2f} s = "
              f"{statistics.median(latencies) / t_direct:.1f} x the direct call, worst {latencies[-1]:.2f} s = "
              f"{latencies[-1] / t_direct:.1f} x; all in {wall:.2f} s = {wall / (args.n * t_direct):.2f} x "
              f"{args.n} direct calls in a row")
    finally:
        stop()
    return 0 if answered == args.n else 1


if __name__ == "__main__":
    sys.exit(main())
